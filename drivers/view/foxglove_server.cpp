// Built as C++17: websocketpp 0.8's headers declare constructors with template arguments, which C++20
// forbids (GCC 12 rejects them). Only this file includes them; its header is plain C++17.
#include "drivers/view/foxglove_server.h"

#define ASIO_STANDALONE
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "voca/core/error.h"

namespace voca::view {

namespace {

using WsServer = websocketpp::server<websocketpp::config::asio>;
using Handle = websocketpp::connection_hdl;
using Json = nlohmann::json;

constexpr const char* kSubprotocol = "foxglove.websocket.v1";
constexpr std::uint8_t kMessageDataOpcode = 0x01;
constexpr std::size_t kMessageDataHeaderBytes = 1 + 4 + 8;
// A client that sends this many requests the protocol does not allow is disconnected; the first few
// are logged, the rest only counted.
constexpr int kMaxBadRequests = 20;
constexpr int kLoggedBadRequests = 3;
constexpr std::size_t kMaxSubscriptionsPerClient = 256;
// The close handshake a client gets at the end before it is cut off.
constexpr auto kCloseGrace = std::chrono::milliseconds(500);
constexpr auto kCutOffGrace = std::chrono::milliseconds(500);

std::string statusMessage(int level, const std::string& message) {
  return Json{{"op", "status"}, {"level", level}, {"message", message}}.dump();
}

void putLittleEndian(std::uint8_t* out, std::uint64_t value, int bytes) {
  for (int i = 0; i < bytes; ++i) out[i] = static_cast<std::uint8_t>(value >> (8 * i));
}

bool isWildcard(const std::string& host) { return host == "0.0.0.0" || host == "::" || host.empty(); }

std::string urlHost(const std::string& host) {
  if (isWildcard(host)) {
    std::error_code ec;
    const std::string name = asio::ip::host_name(ec);
    return ec || name.empty() ? "localhost" : name;
  }
  return host.find(':') != std::string::npos ? "[" + host + "]" : host;
}

}  // namespace

ServerAddress parseServerAddress(const std::string& text) {
  const auto bad = [&](const std::string& why) {
    return InputError(
        fmt::format("{}: {}; expected [host:]port, e.g. 8765, 127.0.0.1:8765 or [::1]:8765 (port 0 "
                    "picks a free one)",
                    text.empty() ? "an empty address" : "\"" + text + "\"", why));
  };
  ServerAddress address;
  address.text = text;
  std::string port_text = text;
  if (!text.empty() && text.front() == '[') {
    const std::size_t close = text.find(']');
    if (close == std::string::npos || close + 1 >= text.size() || text[close + 1] != ':') {
      throw bad("an IPv6 host in brackets needs its port after \"]:\"");
    }
    address.host = text.substr(1, close - 1);
    port_text = text.substr(close + 2);
  } else if (const std::size_t colon = text.rfind(':'); colon != std::string::npos) {
    if (text.find(':') != colon) throw bad("an IPv6 host goes in brackets");
    address.host = text.substr(0, colon);
    port_text = text.substr(colon + 1);
  } else {
    address.host = "0.0.0.0";
  }
  if (address.host.empty()) throw bad("the host before ':' is empty");
  if (port_text.empty() || port_text.size() > 5 ||
      !std::all_of(port_text.begin(), port_text.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    throw bad(port_text.empty() ? "no port" : "the port \"" + port_text + "\" is not a number");
  }
  address.port = std::stoi(port_text);
  if (address.port > 65535) throw bad("the port is above 65535");
  return address;
}

struct FoxgloveServer::Impl {
  ServerOptions options;
  std::string server_info;  // the serverInfo and advertise messages, made once
  std::string advertise;

  asio::io_context io;  // before server: its acceptor and connections use it until they are gone
  WsServer server;
  std::thread thread;
  std::mutex finished_mutex;
  std::condition_variable finished_changed;
  bool finished = true;  // the thread is not running
  bool stopping = false;
  std::string host;
  int port = 0;

  struct Client {
    std::string name;                                   // its address, for log lines
    std::vector<std::int64_t> subscription_of_channel;  // -1: not subscribed
    std::map<std::uint32_t, std::size_t> channel_of_subscription;
    int bad_requests = 0;
    std::int64_t dropped = 0;  // messages not sent because too much waited for it
  };
  // Guards clients, connections and the parameters' vector (the values are atomics).
  std::mutex mutex;
  std::map<Handle, Client, std::owner_less<Handle>> clients;
  std::vector<Handle> connections;            // every TCP connection (page requests too), for the cut-off at stop()
  std::vector<std::atomic<int>> subscribers;  // per channel
  std::vector<std::atomic<double>> parameters;
  std::vector<std::uint8_t> frame;  // the message data frame being sent

  std::atomic<std::int64_t> connections_total{0}, messages_sent{0}, messages_dropped{0}, bad_requests{0},
      pages_served{0};

  explicit Impl(ServerOptions opts)
      : options(std::move(opts)), subscribers(options.channels.size()), parameters(options.parameters.size()) {
    if (!options.log) options.log = [](const std::string& line) { std::fprintf(stderr, "view: %s\n", line.c_str()); };
    for (std::size_t i = 0; i < parameters.size(); ++i) parameters[i].store(options.parameters[i].value);
    for (std::atomic<int>& count : subscribers) count.store(0);
    Json info = {{"op", "serverInfo"},
                 {"name", options.name},
                 {"capabilities", options.parameters.empty() ? Json::array() : Json::array({"parameters"})},
                 {"supportedEncodings", Json::array()},
                 {"metadata", Json::object()},
                 {"sessionId", std::to_string(std::chrono::system_clock::now().time_since_epoch().count())}};
    server_info = info.dump();
    Json channels = Json::array();
    for (std::size_t i = 0; i < options.channels.size(); ++i) {
      const Channel& c = options.channels[i];
      channels.push_back({{"id", i + 1},
                          {"topic", c.topic},
                          {"encoding", c.encoding},
                          {"schemaName", c.schema_name},
                          {"schema", c.schema},
                          {"schemaEncoding", c.schema_encoding}});
    }
    advertise = Json{{"op", "advertise"}, {"channels", channels}}.dump();
  }

  void log(const std::string& line) const {
    try {
      options.log(line);
    } catch (...) {
      // A log line lost is no reason to stop serving.
    }
  }

  std::string nameOf(const Handle& hdl) {
    std::error_code ec;
    WsServer::connection_ptr con = server.get_con_from_hdl(hdl, ec);
    return ec ? std::string("?") : con->get_remote_endpoint();
  }

  void sendText(const Handle& hdl, const std::string& text) {
    std::error_code ec;
    server.send(hdl, text, websocketpp::frame::opcode::text, ec);
  }

  // Counts a refused request; logs the first few, answers with a status message, and disconnects a
  // client that keeps sending them.
  void refuse(const Handle& hdl, Client& client, const std::string& why) {
    ++bad_requests;
    ++client.bad_requests;
    if (client.bad_requests <= kLoggedBadRequests) {
      log(fmt::format("client {}: {}{}", client.name, why,
                      client.bad_requests == kLoggedBadRequests ? " (further refusals not logged)" : ""));
    }
    sendText(hdl, statusMessage(2, why));
    if (client.bad_requests == kMaxBadRequests) {
      log(fmt::format("client {}: disconnected after {} refused requests", client.name, kMaxBadRequests));
      std::error_code ec;
      server.close(hdl, websocketpp::close::status::policy_violation, "too many invalid requests", ec);
    }
  }

  void onMessage(const Handle& hdl, const WsServer::message_ptr& message) {
    std::lock_guard lock(mutex);
    const auto it = clients.find(hdl);
    if (it == clients.end()) return;
    Client& client = it->second;
    if (message->get_opcode() != websocketpp::frame::opcode::text) {
      refuse(hdl, client,
             "binary messages (client publishing, service calls) are not offered by this server; it takes JSON "
             "requests only");
      return;
    }
    const Json request = Json::parse(message->get_payload(), nullptr, false);
    if (request.is_discarded() || !request.is_object()) {
      refuse(hdl, client, "a request that is not a JSON object");
      return;
    }
    const auto op = request.find("op");
    if (op == request.end() || !op->is_string()) {
      refuse(hdl, client, "a request without a string \"op\"");
      return;
    }
    const std::string& name = op->get_ref<const std::string&>();
    if (name == "subscribe") {
      subscribe(hdl, client, request);
    } else if (name == "unsubscribe") {
      unsubscribe(hdl, client, request);
    } else if (name == "getParameters" && !options.parameters.empty()) {
      getParameters(hdl, client, request);
    } else if (name == "setParameters" && !options.parameters.empty()) {
      setParameters(hdl, client, request);
    } else {
      refuse(hdl, client, fmt::format("op \"{}\" is not supported by this server", name));
    }
  }

  void subscribe(const Handle& hdl, Client& client, const Json& request) {
    const auto list = request.find("subscriptions");
    if (list == request.end() || !list->is_array()) {
      refuse(hdl, client, "subscribe without a \"subscriptions\" array");
      return;
    }
    for (const Json& s : *list) {
      const auto id = s.is_object() ? s.find("id") : s.end();
      const auto channel = s.is_object() ? s.find("channelId") : s.end();
      if (!s.is_object() || id == s.end() || channel == s.end() || !id->is_number_unsigned() ||
          !channel->is_number_unsigned() || id->get<std::uint64_t>() > 0xffffffffu) {
        refuse(hdl, client, "subscribe: each subscription needs an \"id\" (uint32) and a \"channelId\"");
        continue;
      }
      const auto sub = static_cast<std::uint32_t>(id->get<std::uint64_t>());
      const std::uint64_t channel_id = channel->get<std::uint64_t>();
      if (channel_id < 1 || channel_id > options.channels.size()) {
        refuse(hdl, client, fmt::format("subscribe: no channel {}", channel_id));
        continue;
      }
      const std::size_t index = static_cast<std::size_t>(channel_id - 1);
      if (client.channel_of_subscription.count(sub) != 0) {
        refuse(hdl, client, fmt::format("subscribe: subscription id {} is in use", sub));
        continue;
      }
      if (client.subscription_of_channel[index] >= 0) {
        refuse(hdl, client, fmt::format("subscribe: channel {} is subscribed already", channel_id));
        continue;
      }
      if (client.channel_of_subscription.size() >= kMaxSubscriptionsPerClient) {
        refuse(hdl, client, "subscribe: too many subscriptions");
        continue;
      }
      client.channel_of_subscription[sub] = index;
      client.subscription_of_channel[index] = sub;
      ++subscribers[index];
    }
  }

  void unsubscribe(const Handle& hdl, Client& client, const Json& request) {
    const auto list = request.find("subscriptionIds");
    if (list == request.end() || !list->is_array()) {
      refuse(hdl, client, "unsubscribe without a \"subscriptionIds\" array");
      return;
    }
    for (const Json& id : *list) {
      const auto found = id.is_number_unsigned() && id.get<std::uint64_t>() <= 0xffffffffu
                             ? client.channel_of_subscription.find(static_cast<std::uint32_t>(id.get<std::uint64_t>()))
                             : client.channel_of_subscription.end();
      if (found == client.channel_of_subscription.end()) {
        refuse(hdl, client, fmt::format("unsubscribe: no subscription {}", id.dump()));
        continue;
      }
      client.subscription_of_channel[found->second] = -1;
      --subscribers[found->second];
      client.channel_of_subscription.erase(found);
    }
  }

  Json parameterValues(const std::vector<std::size_t>& which, const Json* id) const {
    Json list = Json::array();
    for (const std::size_t i : which) {
      list.push_back({{"name", options.parameters[i].name}, {"value", parameters[i].load()}, {"type", "float64"}});
    }
    Json reply = {{"op", "parameterValues"}, {"parameters", list}};
    if (id != nullptr && id->is_string()) reply["id"] = *id;
    return reply;
  }

  std::optional<std::size_t> findParameter(const std::string& name) const {
    for (std::size_t i = 0; i < options.parameters.size(); ++i) {
      if (options.parameters[i].name == name) return i;
    }
    return std::nullopt;
  }

  void getParameters(const Handle& hdl, Client& client, const Json& request) {
    const auto names = request.find("parameterNames");
    std::vector<std::size_t> which;
    if (names == request.end() || !names->is_array()) {
      refuse(hdl, client, "getParameters without a \"parameterNames\" array");
      return;
    }
    for (const Json& name : *names) {
      if (!name.is_string()) continue;
      if (const auto i = findParameter(name.get<std::string>())) which.push_back(*i);
    }
    if (names->empty()) {
      for (std::size_t i = 0; i < options.parameters.size(); ++i) which.push_back(i);
    }
    const auto id = request.find("id");
    sendText(hdl, parameterValues(which, id == request.end() ? nullptr : &*id).dump());
  }

  void setParameters(const Handle& hdl, Client& client, const Json& request) {
    const auto list = request.find("parameters");
    if (list == request.end() || !list->is_array()) {
      refuse(hdl, client, "setParameters without a \"parameters\" array");
      return;
    }
    std::vector<std::size_t> changed;
    for (const Json& p : *list) {
      const auto name = p.is_object() ? p.find("name") : p.end();
      const auto value = p.is_object() ? p.find("value") : p.end();
      if (!p.is_object() || name == p.end() || !name->is_string()) {
        refuse(hdl, client, "setParameters: each parameter needs a \"name\"");
        continue;
      }
      const auto index = findParameter(name->get<std::string>());
      if (!index) {
        refuse(hdl, client, fmt::format("setParameters: no parameter {}", name->dump()));
        continue;
      }
      const NumericParameter& spec = options.parameters[*index];
      if (value == p.end() || !value->is_number() || !(value->get<double>() >= spec.min) ||
          !(value->get<double>() <= spec.max)) {
        refuse(hdl, client,
               fmt::format("setParameters: {} takes a number from {} to {}", spec.name, spec.min, spec.max));
        continue;
      }
      parameters[*index].store(value->get<double>());
      changed.push_back(*index);
      log(fmt::format("client {} set {} to {}", client.name, spec.name, value->get<double>()));
    }
    // The new values; always when the request has an id (the spec's answer), else when any changed.
    const auto id = request.find("id");
    if (id != request.end() || !changed.empty()) {
      sendText(hdl, parameterValues(changed, id == request.end() ? nullptr : &*id).dump());
    }
  }

  bool onValidate(const Handle& hdl) {
    WsServer::connection_ptr con = server.get_con_from_hdl(hdl);
    const std::vector<std::string>& offered = con->get_requested_subprotocols();
    if (std::find(offered.begin(), offered.end(), kSubprotocol) == offered.end()) {
      ++bad_requests;
      log(fmt::format("client {}: refused, it did not ask for the WebSocket subprotocol {}", con->get_remote_endpoint(),
                      kSubprotocol));
      return false;
    }
    {
      std::lock_guard lock(mutex);
      if (static_cast<int>(clients.size()) >= options.max_clients) {
        log(fmt::format("client {}: refused, {} clients are connected already", con->get_remote_endpoint(),
                        clients.size()));
        con->set_status(websocketpp::http::status_code::service_unavailable);
        return false;
      }
    }
    con->select_subprotocol(kSubprotocol);
    return true;
  }

  void onOpen(const Handle& hdl) {
    Client client;
    client.name = nameOf(hdl);
    client.subscription_of_channel.assign(options.channels.size(), -1);
    std::size_t connected = 0;
    {
      std::lock_guard lock(mutex);
      clients.emplace(hdl, client);
      connected = clients.size();
    }
    ++connections_total;
    log(fmt::format("client {} connected ({} connected)", client.name, connected));
    sendText(hdl, server_info);
    sendText(hdl, advertise);
  }

  void onClose(const Handle& hdl) {
    Client client;
    std::size_t connected = 0;
    {
      std::lock_guard lock(mutex);
      const auto it = clients.find(hdl);
      if (it == clients.end()) return;
      client = std::move(it->second);
      for (std::size_t c = 0; c < client.subscription_of_channel.size(); ++c) {
        if (client.subscription_of_channel[c] >= 0) --subscribers[c];
      }
      clients.erase(it);
      connected = clients.size();
    }
    std::string reason;
    std::error_code ec;
    if (WsServer::connection_ptr con = server.get_con_from_hdl(hdl, ec)) {
      const std::string code = websocketpp::close::status::get_string(con->get_remote_close_code());
      reason = con->get_ec() ? con->get_ec().message() : code;
    }
    log(fmt::format("client {} disconnected ({}){}; {} connected", client.name, reason,
                    client.dropped > 0
                        ? fmt::format(", {} messages dropped for it while it read too slowly", client.dropped)
                        : std::string(),
                    connected));
  }

  void onHttp(const Handle& hdl) {
    WsServer::connection_ptr con = server.get_con_from_hdl(hdl);
    const std::string& method = con->get_request().get_method();
    const std::string& resource = con->get_resource();
    con->append_header("Cache-Control", "no-store");
    if (method != "GET") {
      con->set_status(websocketpp::http::status_code::method_not_allowed);
      con->append_header("Allow", "GET");
      return;
    }
    const std::string path = resource.substr(0, resource.find('?'));
    if ((path == "/" || path == "/index.html") && !options.page_html.empty()) {
      con->set_status(websocketpp::http::status_code::ok);
      con->append_header("Content-Type", "text/html; charset=utf-8");
      con->set_body(options.page_html);
      ++pages_served;
      return;
    }
    con->set_status(websocketpp::http::status_code::not_found);
    con->append_header("Content-Type", "text/plain; charset=utf-8");
    con->set_body(fmt::format("{} is not here: the live view is at /, Foxglove connects with ws://\n", path));
  }

  void onSocketInit(const Handle& hdl, asio::ip::tcp::socket& socket) {
    std::error_code ec;
    socket.set_option(asio::ip::tcp::no_delay(true), ec);  // small messages (poses) without Nagle's delay
    std::lock_guard lock(mutex);
    connections.erase(
        std::remove_if(connections.begin(), connections.end(), [](const Handle& h) { return h.expired(); }),
        connections.end());
    connections.push_back(hdl);
  }

  void run() {
    for (;;) {
      try {
        io.run();
        break;
      } catch (const std::exception& e) {
        log(fmt::format("internal error, serving on: {}", e.what()));
      }
    }
    std::lock_guard lock(finished_mutex);
    finished = true;
    finished_changed.notify_all();
  }

  bool waitFinished(std::chrono::milliseconds timeout) {
    std::unique_lock lock(finished_mutex);
    return finished_changed.wait_for(lock, timeout, [&] { return finished; });
  }
};

FoxgloveServer::FoxgloveServer(ServerOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {
  Impl& d = *impl_;
  d.server.clear_access_channels(websocketpp::log::alevel::all);
  d.server.clear_error_channels(websocketpp::log::elevel::all);
  d.server.init_asio(&d.io);
  d.server.set_reuse_addr(true);
  d.server.set_max_message_size(d.options.max_client_message_bytes);
  d.server.set_max_http_body_size(d.options.max_client_message_bytes);
  d.server.set_open_handshake_timeout(5000);
  d.server.set_close_handshake_timeout(static_cast<long>(kCloseGrace.count()));
  d.server.set_validate_handler([&d](Handle hdl) { return d.onValidate(hdl); });
  d.server.set_open_handler([&d](Handle hdl) { d.onOpen(hdl); });
  d.server.set_close_handler([&d](Handle hdl) { d.onClose(hdl); });
  d.server.set_fail_handler([&d](Handle hdl) {
    std::error_code ec;
    WsServer::connection_ptr con = d.server.get_con_from_hdl(hdl, ec);
    // The accept waiting for the next connection ends this way when the server stops: no client.
    if (!con || con->get_ec() == asio::error::operation_aborted) return;
    // A client that hung up or sent garbage during the handshake, a port scanner: worth a line.
    d.log(fmt::format("connection from {} failed: {}", con->get_remote_endpoint(), con->get_ec().message()));
  });
  d.server.set_message_handler([&d](Handle hdl, WsServer::message_ptr message) { d.onMessage(hdl, message); });
  d.server.set_http_handler([&d](Handle hdl) { d.onHttp(hdl); });
  d.server.set_socket_init_handler([&d](Handle hdl, asio::ip::tcp::socket& socket) { d.onSocketInit(hdl, socket); });
}

FoxgloveServer::~FoxgloveServer() { stop(); }

void FoxgloveServer::start(const ServerAddress& address) {
  Impl& d = *impl_;
  if (d.thread.joinable()) throw InputError(fmt::format("{}: the view server is running already", address.text));
  const std::string where = fmt::format("cannot serve the view on {}", address.text);
  std::error_code ec;
  asio::ip::tcp::resolver resolver(d.io);
  const auto resolved =
      resolver.resolve(address.host, std::to_string(address.port), asio::ip::resolver_base::passive, ec);
  if (ec || resolved.empty()) {
    throw InputError(
        fmt::format("{}: cannot resolve the host \"{}\" ({}); give an address of this machine, or a "
                    "port alone to listen on all of them",
                    where, address.host, ec ? ec.message() : "no address"));
  }
  const asio::ip::tcp::endpoint endpoint = resolved.begin()->endpoint();
  d.server.listen(endpoint, ec);
  if (ec) {
    // asio reports the OS's errno in a category of its own, so the codes are compared as numbers.
    const auto is = [&](int code) { return ec.category() == asio::error::get_system_category() && ec.value() == code; };
    std::string hint = "choose another address or port (port 0 picks a free one)";
    if (is(EADDRINUSE)) {
      hint = fmt::format(
          "another program listens on port {}: stop it, or choose another port (port 0 picks a free "
          "one)",
          address.port);
    } else if (is(EADDRNOTAVAIL)) {
      hint = fmt::format("{} is not an address of this machine: use one of its addresses, or 0.0.0.0 for all",
                         address.host);
    } else if (is(EACCES)) {
      hint = "ports below 1024 need root: use a port from 1024 up";
    }
    throw InputError(fmt::format("{}: {}; {}", where, ec.message(), hint));
  }
  d.port = d.server.get_local_endpoint(ec).port();
  d.host = address.host;
  d.server.start_accept(ec);
  if (ec) throw InputError(fmt::format("{}: cannot accept connections ({})", where, ec.message()));
  d.finished = false;
  d.stopping = false;
  d.thread = std::thread([&d] { d.run(); });
}

int FoxgloveServer::port() const { return impl_->port; }

std::string FoxgloveServer::pageUrl() const { return fmt::format("http://{}:{}/", urlHost(impl_->host), impl_->port); }

std::string FoxgloveServer::websocketUrl() const {
  return fmt::format("ws://{}:{}", urlHost(impl_->host), impl_->port);
}

bool FoxgloveServer::subscribed(std::size_t channel) const {
  return channel < impl_->subscribers.size() && impl_->subscribers[channel].load(std::memory_order_relaxed) > 0;
}

double FoxgloveServer::parameter(std::size_t index) const {
  return index < impl_->parameters.size() ? impl_->parameters[index].load(std::memory_order_relaxed) : 0.0;
}

void FoxgloveServer::publish(std::size_t channel, std::uint64_t timestamp_ns, const void* payload, std::size_t size) {
  Impl& d = *impl_;
  if (!subscribed(channel)) return;
  std::lock_guard lock(d.mutex);
  if (d.stopping) return;
  d.frame.resize(kMessageDataHeaderBytes + size);
  d.frame[0] = kMessageDataOpcode;
  putLittleEndian(d.frame.data() + 5, timestamp_ns, 8);
  std::memcpy(d.frame.data() + kMessageDataHeaderBytes, payload, size);
  for (auto& [hdl, client] : d.clients) {
    const std::int64_t subscription = client.subscription_of_channel[channel];
    if (subscription < 0) continue;
    std::error_code ec;
    WsServer::connection_ptr con = d.server.get_con_from_hdl(hdl, ec);
    if (ec || con->get_state() != websocketpp::session::state::open) continue;
    if (con->get_buffered_amount() + d.frame.size() > d.options.max_client_backlog_bytes) {
      // Said once; how many were dropped is said when the client leaves.
      if (client.dropped++ == 0) {
        d.log(fmt::format("client {} reads too slowly: its messages are dropped while over {} MiB wait for it",
                          client.name, d.options.max_client_backlog_bytes >> 20));
      }
      ++d.messages_dropped;
      continue;
    }
    putLittleEndian(d.frame.data() + 1, static_cast<std::uint64_t>(subscription), 4);
    con->send(d.frame.data(), d.frame.size(), websocketpp::frame::opcode::binary);
    ++d.messages_sent;
  }
}

ServerCounters FoxgloveServer::counters() const {
  Impl& d = *impl_;
  ServerCounters c;
  {
    std::lock_guard lock(d.mutex);
    c.clients = static_cast<std::int64_t>(d.clients.size());
  }
  c.connections = d.connections_total.load();
  c.messages_sent = d.messages_sent.load();
  c.messages_dropped = d.messages_dropped.load();
  c.bad_requests = d.bad_requests.load();
  c.pages_served = d.pages_served.load();
  return c;
}

void FoxgloveServer::stop() {
  Impl& d = *impl_;
  if (!d.thread.joinable()) return;
  {
    std::lock_guard lock(d.mutex);
    d.stopping = true;
  }
  // A close frame to every client, and no new connections.
  asio::post(d.io, [&d] {
    std::error_code ec;
    d.server.stop_listening(ec);
    std::vector<Handle> open;
    {
      std::lock_guard lock(d.mutex);
      for (const auto& entry : d.clients) open.push_back(entry.first);
    }
    for (const Handle& hdl : open) d.server.close(hdl, websocketpp::close::status::going_away, "the run ended", ec);
  });
  if (!d.waitFinished(kCloseGrace)) {
    // Clients that did not answer (one that stopped reading never sees the close frame) and page
    // requests in flight: their sockets are closed under them.
    asio::post(d.io, [&d] {
      std::vector<Handle> all;
      {
        std::lock_guard lock(d.mutex);
        all = d.connections;
      }
      for (const Handle& hdl : all) {
        std::error_code ec;
        if (WsServer::connection_ptr con = d.server.get_con_from_hdl(hdl, ec)) con->get_raw_socket().close(ec);
      }
    });
    if (!d.waitFinished(kCutOffGrace)) d.io.stop();
  }
  d.thread.join();
  const ServerCounters c = counters();
  if (c.connections == 0 && c.pages_served == 0 && c.bad_requests == 0) return;  // nobody came: nothing to say
  d.log(
      fmt::format("closed: {} client session{}, {} page load{}, {} messages sent, {} dropped for slow clients, {} "
                  "requests refused",
                  c.connections, c.connections == 1 ? "" : "s", c.pages_served, c.pages_served == 1 ? "" : "s",
                  c.messages_sent, c.messages_dropped, c.bad_requests));
}

}  // namespace voca::view
