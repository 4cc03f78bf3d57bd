// The live view's server (drivers/view) without a run: addresses, a port that cannot be bound, the page
// over plain HTTP on the WebSocket port, a refused handshake, and a stop that does not wait for a client
// that never reads. The protocol itself is tested end to end by tests/test_view.py.

#include <arpa/inet.h>
#include <doctest/doctest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>

#include "drivers/view/foxglove_server.h"
#include "drivers/view/view_page.h"
#include "voca/core/error.h"

namespace {

using voca::view::FoxgloveServer;
using voca::view::parseServerAddress;

// A listening TCP socket on 127.0.0.1 (port 0: any free one), closed on destruction.
class Listener {
 public:
  explicit Listener(int port = 0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<std::uint16_t>(port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    REQUIRE(::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
    REQUIRE(::listen(fd_, 4) == 0);
    socklen_t size = sizeof addr;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&addr), &size);
    port_ = ntohs(addr.sin_port);
  }
  ~Listener() { ::close(fd_); }
  int port() const { return port_; }

 private:
  int fd_ = -1;
  int port_ = 0;
};

// Connects to 127.0.0.1:port, sends request, and returns everything the server sends until it closes
// (or 3 s pass).
std::string exchange(int port, const std::string& request) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  REQUIRE(::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
  timeval timeout{3, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  REQUIRE(::send(fd, request.data(), request.size(), 0) == static_cast<ssize_t>(request.size()));
  std::string reply;
  char buffer[4096];
  for (ssize_t n; (n = ::recv(fd, buffer, sizeof buffer, 0)) > 0;) reply.append(buffer, static_cast<std::size_t>(n));
  ::close(fd);
  return reply;
}

voca::view::ServerOptions pageOptions() {
  voca::view::ServerOptions options;
  options.page_html = std::string(voca::view::viewPageHtml());
  options.channels.push_back({"/a", "json", "A", "{}", "jsonschema"});
  options.log = [](const std::string&) {};
  return options;
}

}  // namespace

TEST_CASE("view addresses: a port alone listens everywhere; host:port, [IPv6]:port; bad ones named") {
  CHECK(parseServerAddress("8765").host == "0.0.0.0");
  CHECK(parseServerAddress("8765").port == 8765);
  CHECK(parseServerAddress("127.0.0.1:0").host == "127.0.0.1");
  CHECK(parseServerAddress("127.0.0.1:0").port == 0);
  CHECK(parseServerAddress("robot.local:9000").host == "robot.local");
  CHECK(parseServerAddress("[::1]:8765").host == "::1");
  CHECK(parseServerAddress("[::1]:8765").port == 8765);
  for (const char* bad : {"", "abc", "70000", "host:", ":8765", "::1:8765", "[::1]8765", "1.2.3.4:-1", "8765x"}) {
    INFO(bad);
    CHECK_THROWS_AS(parseServerAddress(bad), voca::InputError);
  }
  CHECK_THROWS_WITH(parseServerAddress("localhost:99999"), doctest::Contains("\"localhost:99999\""));
}

TEST_CASE("a port in use is an InputError naming the address and what to do") {
  const Listener taken;
  FoxgloveServer server(pageOptions());
  const std::string address = "127.0.0.1:" + std::to_string(taken.port());
  const std::string expected = address + ": Address already in use; another program listens on port";
  CHECK_THROWS_WITH_AS(server.start(parseServerAddress(address)), doctest::Contains(expected.c_str()),
                       voca::InputError);
  // An address of no interface here.
  FoxgloveServer elsewhere(pageOptions());
  CHECK_THROWS_WITH_AS(elsewhere.start(parseServerAddress("192.0.2.1:0")),
                       doctest::Contains("192.0.2.1 is not an address of this machine"), voca::InputError);
}

TEST_CASE(
    "the page is served over HTTP on the WebSocket port; other paths 404; a handshake without the subprotocol is "
    "refused") {
  FoxgloveServer server(pageOptions());
  server.start(parseServerAddress("127.0.0.1:0"));
  REQUIRE(server.port() > 0);
  CHECK(server.pageUrl() == "http://127.0.0.1:" + std::to_string(server.port()) + "/");
  CHECK(server.websocketUrl() == "ws://127.0.0.1:" + std::to_string(server.port()));

  const std::string page = exchange(server.port(), "GET / HTTP/1.1\r\nHost: x\r\n\r\n");
  CHECK(page.rfind("HTTP/1.1 200", 0) == 0);
  CHECK(page.find("Content-Type: text/html") != std::string::npos);
  CHECK(page.find("<title>VOCA-RT live view</title>") != std::string::npos);
  CHECK(page.find("foxglove.websocket.v1") != std::string::npos);

  CHECK(exchange(server.port(), "GET /secret HTTP/1.1\r\nHost: x\r\n\r\n").rfind("HTTP/1.1 404", 0) == 0);
  CHECK(exchange(server.port(), "POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 0\r\n\r\n").rfind("HTTP/1.1 405", 0) ==
        0);
  // A WebSocket upgrade that does not ask for foxglove.websocket.v1.
  const std::string refused =
      exchange(server.port(),
               "GET / HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
               "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n");
  CHECK(refused.rfind("HTTP/1.1 400", 0) == 0);
  CHECK(exchange(server.port(), "\x16\x03\x01 not http at all\r\n\r\n").rfind("HTTP/1.1 400", 0) == 0);
  CHECK(server.counters().pages_served == 1);
  CHECK(server.counters().bad_requests >= 1);
  server.stop();
  server.stop();  // idempotent
}

TEST_CASE("stop() closes a connection that never sends or reads within a second") {
  FoxgloveServer server(pageOptions());
  server.start(parseServerAddress("127.0.0.1:0"));
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(server.port()));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  REQUIRE(::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
  // Half a request: the server waits for the rest.
  const std::string half = "GET / HTTP/1.1\r\nHost: x\r\nUpgr";
  REQUIRE(::send(fd, half.data(), half.size(), 0) == static_cast<ssize_t>(half.size()));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const auto start = std::chrono::steady_clock::now();
  server.stop();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  CHECK(seconds < 1.5);
  char byte = 0;
  CHECK(::recv(fd, &byte, 1, 0) <= 0);  // closed by the server
  ::close(fd);
}
