#include "plc/modbus_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace pipeloc {
namespace {

// Keepalive: a peer gone without a FIN (a PLC rebooted, a cable pulled) is noticed after about
// kKeepIdleS + kKeepCount * kKeepIntervalS seconds of silence, even by a connection left idle.
constexpr int kKeepIdleS = 10, kKeepIntervalS = 2, kKeepCount = 3;

void set_client_options(int fd) {
  const int one = 1, idle = kKeepIdleS, interval = kKeepIntervalS, count = kKeepCount;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &one, sizeof one);
  setsockopt(fd, IPPROTO_TCP, TCP_KEEPIDLE, &idle, sizeof idle);
  setsockopt(fd, IPPROTO_TCP, TCP_KEEPINTVL, &interval, sizeof interval);
  setsockopt(fd, IPPROTO_TCP, TCP_KEEPCNT, &count, sizeof count);
}

double ms_since(Clock::time_point then, Clock::time_point now) {
  return std::chrono::duration<double, std::milli>(now - then).count();
}

}  // namespace

bool LogLimiter::allow(Clock::time_point now) {
  if (ms_since(window_start_, now) >= kWindowS * 1000) {
    if (left_out_ > 0)
      spdlog::warn("plc: {} more connection messages in the last {:.0f} s not shown", left_out_, kWindowS);
    window_start_ = now, shown_ = 0, left_out_ = 0;
  }
  if (shown_ < kBurst) return ++shown_, true;
  ++left_out_;
  return false;
}

ModbusServer::ModbusServer(const PlcConfig& cfg) : cfg_(cfg), port_(cfg.port) {
  const std::string where = cfg.address + ":" + std::to_string(cfg.port);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(std::uint16_t(cfg.port));
  if (inet_pton(AF_INET, cfg.address.c_str(), &addr.sin_addr) != 1)
    throw PlcError("plc.address '" + cfg.address + "': expected an IPv4 address such as 0.0.0.0");
  // The context only builds replies: modbus_reply() on each framed request, through the socket
  // of the connection it came from (modbus_set_socket).
  ctx_ = modbus_new_tcp(cfg.address.c_str(), cfg.port);
  if (!ctx_) throw PlcError("plc.address '" + where + "': " + modbus_strerror(errno));
  // Only the map's holding registers exist: reads and writes elsewhere get exception 02.
  mapping_ = modbus_mapping_new_start_address(0, 0, 0, 0, std::uint16_t(cfg.base), reg::kSize, 0, 0);
  if (!mapping_) {
    modbus_free(ctx_);
    throw PlcError(std::string("plc: register map: ") + modbus_strerror(errno));
  }
  listen_fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  const int one = 1;
  if (listen_fd_ >= 0) setsockopt(listen_fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (listen_fd_ < 0 || ::bind(listen_fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0 ||
      ::listen(listen_fd_, kListenBacklog) != 0) {
    const std::string why = std::strerror(errno);
    if (listen_fd_ >= 0) ::close(listen_fd_);
    modbus_mapping_free(mapping_);
    modbus_free(ctx_);
    throw PlcError("plc: cannot listen on " + where + ": " + why);
  }
  socklen_t len = sizeof addr;
  if (getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len) == 0) port_ = ntohs(addr.sin_port);
  conns_.reserve(std::size_t(cfg.max_clients));
  reg::write_initial(cfg_.encoding, map());
}

ModbusServer::~ModbusServer() {
  for (const Connection& c : conns_) ::close(c.fd);
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
std::string ModbusServer::describe() const {
  return "Modbus TCP server on " + cfg_.address + ":" + std::to_string(port_) + ", registers " +
         std::to_string(cfg_.base) + ".." + std::to_string(cfg_.base + reg::kSize - 1) + ", " +
         word_order_name(cfg_.encoding.order) + (cfg_.encoding.scaled_int32 ? " scaled int32" : " float32") +
         ", up to " + std::to_string(cfg_.max_clients) + " clients" +
         (cfg_.plc_addresses.empty() ? ""
                                     : ", the PLC at " + cfg_.plc_addresses.front() +
                                           (cfg_.plc_addresses.size() > 1 ? " and others" : ""));
}

int ModbusServer::client_list(PlcClientInfo* out, int max) const {
  int n = 0;
  for (const Connection& c : conns_) {
    if (n >= max) break;
    PlcClientInfo& info = out[n++];
    std::memcpy(info.ip, c.ip, sizeof info.ip);
    info.plc = c.plc;
    info.requests = c.requests;
    info.connected = c.connected;
    info.last_request = c.last_request;
  }
  return n;
}

// Makes room for one more connection when every slot is taken: the connection quiet the longest
// goes, never one from the PLC's addresses for anyone else. False: no room (all slots are the PLC's).
bool ModbusServer::admit(bool plc, Clock::time_point now) {
  if (int(conns_.size()) < cfg_.max_clients) return true;
  // Connections their peers closed since this round's poll go first, without evicting anyone.
  serve_ready(0, now);
  if (int(conns_.size()) < cfg_.max_clients) return true;
  // A connection that never sent a request (a scanner, a client left idle) goes before one that
  // did; among equals, the one quiet the longest.
  auto quietest = [&](bool from_plc) {
    long best = -1;
    auto before = [](const Connection& a, const Connection& b) {
      return a.requests != b.requests && (a.requests == 0 || b.requests == 0)
                 ? a.requests == 0
                 : a.last_request < b.last_request;
    };
    for (std::size_t i = 0; i < conns_.size(); ++i)
      if (conns_[i].plc == from_plc && (best < 0 || before(conns_[i], conns_[std::size_t(best)])))
        best = long(i);
    return best;
  };
  long victim = quietest(false);
  if (victim < 0 && plc) victim = quietest(true);
  if (victim < 0) return false;
  ++counters_.evicted;
  drop(std::size_t(victim), "closed to make room (plc.max_clients)", now);
  return true;
}

void ModbusServer::accept_clients(Clock::time_point now) {
  // Until EAGAIN or kAcceptsPerRound: a flood of connects neither waits for the next poll timeout
  // nor holds up the clients already connected.
  for (int accepted = 0; accepted < kAcceptsPerRound; ++accepted) {
    sockaddr_in addr{};
    socklen_t len = sizeof addr;
    const int fd =
        ::accept4(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR || errno == ECONNABORTED) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK && log_limit_.allow(now))
        spdlog::warn("plc: accept: {}", std::strerror(errno));  // e.g. out of file descriptors
      return;
    }
    Connection c;
    c.fd = fd;
    inet_ntop(AF_INET, &addr.sin_addr, c.ip, sizeof c.ip);
    for (const std::string& a : cfg_.plc_addresses) c.plc = c.plc || a == c.ip;
    if (!admit(c.plc, now)) {
      ++counters_.refused;
      if (log_limit_.allow(now))
        spdlog::warn("plc: refused {}: all {} connections are the PLC's (plc.max_clients)", c.ip,
                     conns_.size());
      ::close(fd);
      continue;
    }
    set_client_options(fd);
    c.connected = c.last_request = now;
    ++counters_.accepted;
    conns_.push_back(c);
    if (log_limit_.allow(now))
      spdlog::info("plc: client {}{} connected ({} now)", c.ip, c.plc ? " (PLC)" : "", conns_.size());
  }
}

void ModbusServer::drop(std::size_t i, const char* why, Clock::time_point now) {
  if (why) {
    ++counters_.dropped;
    if (log_limit_.allow(now)) spdlog::warn("plc: client {}: {}", conns_[i].ip, why);
  }
  ::close(conns_[i].fd);
  conns_.erase(conns_.begin() + long(i));
}

void ModbusServer::serve_client(std::size_t i, Clock::time_point now) {
  Connection& c = conns_[i];
  for (int served = 0; served < kRequestsPerRound;) {
    int need = mbtcp::kHeaderBytes;
    if (c.have >= mbtcp::kHeaderBytes && (need = mbtcp::adu_bytes(c.buf)) < 0)
      return drop(i, "not Modbus TCP (MBAP header), closed", now);
    if (c.have < need) {
      const ssize_t n = ::recv(c.fd, c.buf + c.have, std::size_t(need - c.have), MSG_DONTWAIT);
      if (n > 0) {
        if (c.have == 0) c.request_started = now;
        c.have += int(n);
        continue;
      }
      if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return;
      return drop(i, n == 0 || errno == ECONNRESET ? nullptr : "receive failed, closed", now);
    }
    ++counters_.requests;
    modbus_set_socket(ctx_, c.fd);
    if (mbtcp::request_exception(c.buf, c.have)) ++counters_.exceptions;
    // A client that does not read its replies fills its socket buffer: the send fails at once
    // (non-blocking) and only that connection goes.
    if (reply_to_request(ctx_, mapping_, cfg_.base, c.buf, c.have) < 0)
      return drop(i, "reply not accepted (the client does not read), closed", now);
    c.have = 0;
    c.last_request = now;
    ++c.requests;
    ++served;
  }
}

void ModbusServer::close_expired(Clock::time_point now) {
  for (std::size_t i = conns_.size(); i-- > 0;) {
    const Connection& c = conns_[i];
    if (c.have > 0 && ms_since(c.request_started, now) > cfg_.request_timeout_ms) {
      drop(i, "request incomplete after plc.request_timeout_ms, closed", now);
    } else if (c.have == 0 && ms_since(c.last_request, now) > cfg_.idle_timeout_ms) {
      ++counters_.idle_closed;
      drop(i, "no request for plc.idle_timeout_ms, closed", now);
    }
  }
}

int ModbusServer::serve_ready(int timeout_ms, Clock::time_point now) {
  pollfd fds[64];
  for (std::size_t i = 0; i < conns_.size(); ++i) fds[i] = {conns_[i].fd, POLLIN, 0};
  const int ready = ::poll(fds, nfds_t(conns_.size()), timeout_ms);
  // From the back, so that dropping a connection leaves the indices still to visit valid.
  for (std::size_t i = conns_.size(); ready > 0 && i-- > 0;)
    if (fds[i].revents) serve_client(i, now);
  return ready;
}

bool ModbusServer::poll(int timeout_ms, int wake_fd, PlcRequest* req) {
  pollfd fds[2 + 64];
  int n = 0;
  fds[n++] = {listen_fd_, POLLIN, 0};
  fds[n++] = {wake_fd, POLLIN, 0};  // a negative fd is ignored by poll()
  for (const Connection& c : conns_) fds[n++] = {c.fd, POLLIN, 0};
  const int ready = ::poll(fds, nfds_t(n), timeout_ms);  // EINTR (a signal): straight on
  const Clock::time_point now = Clock::now();
  if (ready > 0) {
    for (std::size_t i = conns_.size(); i-- > 0;)
      if (fds[2 + i].revents) serve_client(i, now);
  }
  close_expired(now);
  if (ready > 0 && fds[0].revents) accept_clients(now);
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
