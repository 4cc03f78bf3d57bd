#pragma once
// A Foxglove WebSocket protocol v1 server (subprotocol foxglove.websocket.v1; spec: foxglove/ws-protocol
// docs/spec.md) that also serves one web page over plain HTTP on the same port. Foxglove and
// Lichtblick connect to it as to a ROS bridge: on connecting, a client gets serverInfo and the
// advertised channels with their schemas; it subscribes and receives each message as a binary frame
// (opcode 0x01, uint32 subscription id, uint64 timestamp in ns, payload). With the "parameters"
// capability a client reads and sets the numeric parameters the server declares.
//
// The server runs on a thread of its own. publish() never waits for a client: a client whose unsent
// data exceeds a bound misses messages (counted) until it catches up, so a slow or stalled client costs
// neither memory nor time. A client that sends something the protocol does not allow is answered with
// a status message and, after repeated offences, disconnected; either way a log line says so.
//
// This header is also compiled as C++17 (the WebSocket library's headers are not C++20-clean).

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace voca::view {

// "[host:]port" as given on a command line; a bare port listens on every interface (0.0.0.0).
struct ServerAddress {
  std::string host;  // as given, or "0.0.0.0"
  int port = 0;      // 0: the OS picks a free port
  std::string text;  // as the user wrote it, for messages
};
// Throws InputError naming the text when it is not [host:]port with a port from 0 to 65535
// (IPv6 hosts in brackets: [::1]:8765).
ServerAddress parseServerAddress(const std::string& text);

struct Channel {
  std::string topic;
  std::string encoding;  // message encoding, e.g. "json"
  std::string schema_name;
  std::string schema;
  std::string schema_encoding;  // e.g. "jsonschema"
};

// A float64 parameter that clients may read and set (setParameters) within [min, max].
struct NumericParameter {
  std::string name;
  double value = 0.0;
  double min = 0.0, max = 0.0;
};

struct ServerOptions {
  std::string name = "voca";                 // serverInfo's name
  std::vector<Channel> channels;             // channel i is advertised with id i + 1
  std::vector<NumericParameter> parameters;  // the "parameters" capability when non-empty
  std::string page_html;                     // served at GET / (and /index.html); empty: 404
  // A client's data not yet handed to the OS above this is a slow client: its messages are dropped.
  // 4 MiB: some 40 camera images, far behind live already.
  std::size_t max_client_backlog_bytes = std::size_t{4} << 20;
  // Largest message a client may send (the protocol's requests are small).
  std::size_t max_client_message_bytes = std::size_t{64} << 10;
  int max_clients = 16;
  // Where log lines go (connections, bad requests, slow clients); default: stderr, prefixed "view: ".
  std::function<void(const std::string&)> log;
};

struct ServerCounters {
  std::int64_t clients = 0;           // connected now (WebSocket)
  std::int64_t connections = 0;       // WebSocket sessions since the start
  std::int64_t messages_sent = 0;     // message data frames handed to clients
  std::int64_t messages_dropped = 0;  // not sent because the client's backlog was over the bound
  std::int64_t bad_requests = 0;      // client messages refused (invalid JSON, unknown op, binary, ...)
  std::int64_t pages_served = 0;      // HTTP GET of the page
};

class FoxgloveServer {
 public:
  explicit FoxgloveServer(ServerOptions options);
  ~FoxgloveServer();  // stop()
  FoxgloveServer(const FoxgloveServer&) = delete;
  FoxgloveServer& operator=(const FoxgloveServer&) = delete;

  // Binds and starts serving on a thread of its own. Throws InputError naming the address when it
  // cannot be resolved or bound (in use, not an address of this machine, a privileged port).
  void start(const ServerAddress& address);
  // The port bound (the one the OS picked for port 0), and the URLs to open: for a wildcard address
  // they name this machine's host name.
  int port() const;
  std::string pageUrl() const;       // http://host:port/
  std::string websocketUrl() const;  // ws://host:port

  // From any one thread at a time (the publisher): whether any client subscribes to channel index i,
  // and the message to every subscriber whose backlog allows it. Never blocks on a client.
  bool subscribed(std::size_t channel) const;
  void publish(std::size_t channel, std::uint64_t timestamp_ns, const void* payload, std::size_t size);
  // The current value of parameter index i (as clients set it).
  double parameter(std::size_t index) const;

  ServerCounters counters() const;

  // Closes every connection (a close frame to each client; a client that does not answer within half a
  // second is cut off) and joins the thread. Idempotent.
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace voca::view
