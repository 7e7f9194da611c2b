// Fuzz target: the bytes a Modbus TCP client can send, through libmodbus's receive and the
// server's reply (reply_to_request) on the register map, over a real socket pair.
#include <modbus/modbus.h>
#include <sys/socket.h>
#include <unistd.h>

#include <csignal>
#include <cstdint>

#include "plc/modbus_server.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static modbus_t* ctx = [] {
    std::signal(SIGPIPE, SIG_IGN);
    modbus_t* c = modbus_new_tcp("127.0.0.1", 1502);
    pipeloc::set_server_timeouts(c, 1);
    return c;
  }();
  static modbus_mapping_t* mapping =
      modbus_mapping_new_start_address(0, 0, 0, 0, 0, pipeloc::reg::kSize, 0, 0);
  int fds[2];
  if (socketpair(AF_UNIX, SOCK_STREAM, 0, fds) != 0 || size > 60000) return 0;
  std::size_t sent = 0;
  while (sent < size) {
    const ssize_t n = ::write(fds[1], data + sent, size - sent);
    if (n <= 0) break;
    sent += std::size_t(n);
  }
  shutdown(fds[1], SHUT_WR);
  modbus_set_socket(ctx, fds[0]);
  std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
  for (int i = 0; i < 1000; ++i) {
    const int rc = modbus_receive(ctx, query);
    if (rc < 0) break;
    if (rc > 0 && pipeloc::reply_to_request(ctx, mapping, 0, query, rc) < 0) break;
  }
  ::close(fds[0]);
  ::close(fds[1]);
  return 0;
}
