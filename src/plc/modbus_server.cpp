#include "plc/modbus_server.hpp"

#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <spdlog/spdlog.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace pipeloc {
namespace {

// Function codes that write holding registers (Modbus Application Protocol v1.1b3, 6.6-6.17).
constexpr int kWriteSingle = 0x06, kWriteMultiple = 0x10, kMaskWrite = 0x16, kReadWriteMultiple = 0x17;

int u16(const std::uint8_t* p) { return (p[0] << 8) | p[1]; }

// The registers [first, first + count) a request writes, if it writes any.
bool written_range(const std::uint8_t* req, int header, int length, int* first, int* count) {
  const std::uint8_t* pdu = req + header;
  const int pdu_len = length - header;
  if (pdu_len < 1) return false;
  switch (pdu[0]) {
    case kWriteSingle:
    case kMaskWrite:
      if (pdu_len < 3) return false;
      *first = u16(pdu + 1), *count = 1;
      return true;
    case kWriteMultiple:
      if (pdu_len < 5) return false;
      *first = u16(pdu + 1), *count = u16(pdu + 3);
      return true;
    case kReadWriteMultiple:
      if (pdu_len < 9) return false;
      *first = u16(pdu + 5), *count = u16(pdu + 7);
      return true;
    default:
      return false;
  }
}

void set_socket_timeouts(int fd, int ms) {
  timeval tv{ms / 1000, (ms % 1000) * 1000};
  setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
  const int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
}

}  // namespace

ModbusServer::ModbusServer(const PlcConfig& cfg) : cfg_(cfg), port_(cfg.port) {
  const std::string where = cfg.address + ":" + std::to_string(cfg.port);
  ctx_ = modbus_new_tcp(cfg.address.c_str(), cfg.port);
  if (!ctx_) throw PlcError("plc.address '" + where + "': " + modbus_strerror(errno));
  set_server_timeouts(ctx_, cfg.byte_timeout_ms);
  // Only the map's holding registers exist: reads and writes elsewhere get exception 02.
  mapping_ = modbus_mapping_new_start_address(0, 0, 0, 0, std::uint16_t(cfg.base), reg::kSize, 0, 0);
  if (!mapping_) {
    modbus_free(ctx_);
    throw PlcError(std::string("plc: register map: ") + modbus_strerror(errno));
  }
  listen_fd_ = modbus_tcp_listen(ctx_, cfg.max_clients);
  if (listen_fd_ < 0) {
    const std::string why = modbus_strerror(errno);
    modbus_mapping_free(mapping_);
    modbus_free(ctx_);
    throw PlcError("plc: cannot listen on " + where + ": " + why);
  }
  clients_.reserve(std::size_t(cfg.max_clients));
  reg::write_initial(cfg_.encoding, map());
}

ModbusServer::~ModbusServer() {
  for (int fd : clients_) ::close(fd);
  if (listen_fd_ >= 0) ::close(listen_fd_);
  modbus_mapping_free(mapping_);
  modbus_free(ctx_);
}

std::uint16_t* ModbusServer::map() { return mapping_->tab_registers; }
const std::uint16_t* ModbusServer::registers() const { return mapping_->tab_registers; }

void ModbusServer::set_busy() { reg::write_busy(cfg_.encoding, map()); }
void ModbusServer::publish(const reg::Result& r, std::uint16_t ack_id) {
  reg::write_result(r, ack_id, cfg_.encoding, map());
}
void ModbusServer::heartbeat() { ++map()[reg::kHeartbeat]; }

void ModbusServer::accept_client() {
  sockaddr_in addr{};
  socklen_t len = sizeof addr;
  const int fd = ::accept(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
  if (fd < 0) return;
  char ip[INET_ADDRSTRLEN] = "?";
  inet_ntop(AF_INET, &addr.sin_addr, ip, sizeof ip);
  if (int(clients_.size()) >= cfg_.max_clients) {
    ++counters_.refused;
    spdlog::warn("plc: refused a connection from {}: {} clients already (plc.max_clients)", ip,
                 clients_.size());
    ::close(fd);
    return;
  }
  set_socket_timeouts(fd, cfg_.byte_timeout_ms);
  clients_.push_back(fd);
  spdlog::info("plc: client {} connected ({} now)", ip, clients_.size());
}

void ModbusServer::drop_client(std::size_t i) {
  ::close(clients_[i]);
  clients_.erase(clients_.begin() + long(i));
}

void ModbusServer::serve_client(std::size_t i) {
  std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
  modbus_set_socket(ctx_, clients_[i]);
  const int rc = modbus_receive(ctx_, query);
  if (rc == 0) return;  // not for this unit: ignored
  if (rc < 0) {         // closed, garbage or stalled mid-request: this connection only
    if (errno != ECONNRESET) {
      ++counters_.dropped;
      spdlog::warn("plc: dropped a client: {}", modbus_strerror(errno));
    }
    drop_client(i);
    return;
  }
  ++counters_.requests;
  if (reply_to_request(ctx_, mapping_, cfg_.base, query, rc) < 0) drop_client(i);
}

void set_server_timeouts(modbus_t* ctx, int byte_timeout_ms) {
  const auto timeout_us = std::uint32_t(byte_timeout_ms) * 1000u;
  modbus_set_byte_timeout(ctx, timeout_us / 1000000u, timeout_us % 1000000u);
  modbus_set_indication_timeout(ctx, timeout_us / 1000000u, timeout_us % 1000000u);
  modbus_set_response_timeout(ctx, 0, 1000);
}

int reply_to_request(modbus_t* ctx, modbus_mapping_t* mapping, int base, const std::uint8_t* query,
                     int length) {
  const int header = modbus_get_header_length(ctx);
  int first = 0, count = 0;
  if (written_range(query, header, length, &first, &count) &&
      (first < base || first + count > base + reg::kReqId + 1))
    // Only CMD and REQ_ID belong to the PLC; the rest is the service's.
    return modbus_reply_exception(ctx, query, MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  return modbus_reply(ctx, query, length, mapping);
}

bool ModbusServer::poll(int timeout_ms, int wake_fd, PlcRequest* req) {
  fd_set fds;
  FD_ZERO(&fds);
  FD_SET(listen_fd_, &fds);
  int max_fd = listen_fd_;
  for (int fd : clients_) FD_SET(fd, &fds), max_fd = std::max(max_fd, fd);
  if (wake_fd >= 0) FD_SET(wake_fd, &fds), max_fd = std::max(max_fd, wake_fd);
  timeval tv{timeout_ms / 1000, (timeout_ms % 1000) * 1000};
  const int n = ::select(max_fd + 1, &fds, nullptr, nullptr, &tv);
  if (n <= 0) return false;
  // From the back, so that dropping a client leaves the indices still to visit valid.
  for (std::size_t i = clients_.size(); i-- > 0;)
    if (FD_ISSET(clients_[i], &fds)) serve_client(i);
  if (FD_ISSET(listen_fd_, &fds)) accept_client();
  // Each change of REQ_ID submits CMD once; two changes within one round run the later.
  const std::uint16_t req_id = map()[reg::kReqId];
  if (req_id == last_req_id_) return false;
  last_req_id_ = req_id;
  req->command = map()[reg::kCmd];
  req->req_id = req_id;
  req->at = Clock::now();
  return true;
}

}  // namespace pipeloc
