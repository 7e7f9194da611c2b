// Fuzz target: the bytes a Modbus TCP client can send, framed as the server frames them (MBAP
// length, mbtcp::adu_bytes) and answered by reply_to_request on the register map, the replies
// going out through a real socket pair.
#include <modbus/modbus.h>
#include <sys/socket.h>
#include <unistd.h>

#include <csignal>
#include <cstdint>
#include <cstring>

#include "plc/modbus_request.hpp"
#include "plc/register_map.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static modbus_t* ctx = [] {
    std::signal(SIGPIPE, SIG_IGN);
    return modbus_new_tcp("127.0.0.1", 1502);
  }();
  static modbus_mapping_t* mapping =
      modbus_mapping_new_start_address(0, 0, 0, 0, 0, pipeloc::reg::kSize, 0, 0);
  int fds[2];
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, fds) != 0) return 0;
  modbus_set_socket(ctx, fds[0]);
  std::uint8_t adu[pipeloc::mbtcp::kMaxAduBytes];
  std::uint8_t sink[4096];
  for (std::size_t at = 0; at + pipeloc::mbtcp::kHeaderBytes <= size;) {
    const int n = pipeloc::mbtcp::adu_bytes(data + at);
    if (n < 0 || at + std::size_t(n) > size) break;  // the server closes such a connection
    std::memcpy(adu, data + at, std::size_t(n));
    if (pipeloc::reply_to_request(ctx, mapping, 0, adu, n) < 0) break;
    while (::read(fds[1], sink, sizeof sink) > 0) {
    }
    at += std::size_t(n);
  }
  ::close(fds[0]);
  ::close(fds[1]);
  return 0;
}
