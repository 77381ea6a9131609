#include "bridge_server.hpp"

#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace polarslam {
namespace {

namespace fs = std::filesystem;
using Server = websocketpp::server<websocketpp::config::asio>;
using Handle = websocketpp::connection_hdl;

constexpr size_t kMaxSocketBacklog = 512 * 1024;  // bytes websocketpp may hold for a client before we stop handing it more
constexpr long kFlushPeriodMs = 20;
constexpr size_t kMaxPageFileBytes = 4 * 1024 * 1024;

std::string contentType(const fs::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".svg") return "image/svg+xml";
  if (ext == ".png") return "image/png";
  return "application/octet-stream";
}

struct PageFile {
  std::string type, body;
};

/// The page's files, read once: a request can only ever name one of these (no path walking).
std::map<std::string, PageFile> loadPage(const std::string& root) {
  std::map<std::string, PageFile> files;
  if (root.empty()) return files;
  if (!fs::is_directory(root)) throw std::runtime_error("web page folder not found: " + root);
  for (const auto& entry : fs::directory_iterator(root)) {
    if (!entry.is_regular_file() || entry.file_size() > kMaxPageFileBytes) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    std::stringstream body;
    body << in.rdbuf();
    files["/" + entry.path().filename().string()] = {contentType(entry.path()), body.str()};
  }
  if (!files.count("/index.html")) throw std::runtime_error("no index.html in " + root);
  files["/"] = files["/index.html"];
  return files;
}

}  // namespace

struct BridgeServer::Impl {
  struct Client {
    Client(const foxglove::ChannelTable& channels, const ServerOptions& options)
        : session(channels, options.publish_topics), queue(options.queue_capacity, options.queue_bytes) {}
    foxglove::ClientSession session;
    foxglove::FrameQueue queue;
    std::string address;
  };

  Impl(ServerOptions o, const foxglove::ChannelTable& c, std::atomic<size_t>& count)
      : options(std::move(o)), channels(c), client_count(count), page(loadPage(options.web_root)) {}

  ServerOptions options;
  const foxglove::ChannelTable& channels;
  std::atomic<size_t>& client_count;
  std::map<std::string, PageFile> page;
  Server server;
  std::thread thread;
  std::map<Handle, Client, std::owner_less<Handle>> clients;  // io thread only
  std::mutex events_mutex;
  ServerEvents events;
  mutable std::mutex subscribed_mutex;
  std::set<uint32_t> subscribed;  // channels some client subscribes to
  Server::timer_ptr flush_timer;

  void record(const foxglove::ClientSession::Outcome& outcome) {
    std::lock_guard lock(events_mutex);
    events.errors.insert(events.errors.end(), outcome.errors.begin(), outcome.errors.end());
    events.publications.insert(events.publications.end(), outcome.publications.begin(), outcome.publications.end());
  }
  void note(std::string line, std::string error = {}) {
    std::lock_guard lock(events_mutex);
    events.log.push_back(std::move(line));
    if (!error.empty()) events.errors.push_back(std::move(error));
  }

  std::vector<std::string> capabilities() const {
    if (options.publish_topics.empty()) return {};
    return {"clientPublish"};
  }

  bool validate(Handle hdl) {
    Server::connection_ptr con = server.get_con_from_hdl(hdl);
    const std::vector<std::string>& offered = con->get_requested_subprotocols();
    if (std::find(offered.begin(), offered.end(), foxglove::kSubprotocol) == offered.end()) {
      note("refused a WebSocket client that did not offer " + std::string(foxglove::kSubprotocol),
           "client: WebSocket without the foxglove subprotocol");
      return false;
    }
    if (clients.size() >= options.max_clients) {
      con->set_status(websocketpp::http::status_code::service_unavailable);
      note("refused a client: already " + std::to_string(clients.size()) + " connected", "client: too many clients");
      return false;
    }
    con->select_subprotocol(foxglove::kSubprotocol);
    return true;
  }

  void onOpen(Handle hdl) {
    Server::connection_ptr con = server.get_con_from_hdl(hdl);
    auto [it, inserted] = clients.try_emplace(hdl, channels, options);
    it->second.address = con->get_remote_endpoint();
    client_count = clients.size();
    sendText(hdl, foxglove::serverInfoMessage(options.name, capabilities(), options.metadata));
    sendText(hdl, channels.advertiseMessage());
    note("client connected: " + it->second.address + " (" + std::to_string(clients.size()) + " connected)");
  }

  /// After any change of subscriptions (a client's message, a disconnect).
  void updateSubscribed() {
    std::set<uint32_t> now;
    for (const auto& [hdl, client] : clients)
      for (const foxglove::Channel& channel : channels.channels())
        if (client.session.subscriptionFor(channel.id)) now.insert(channel.id);
    std::lock_guard lock(subscribed_mutex);
    subscribed.swap(now);
  }

  void onClose(Handle hdl) {
    const auto it = clients.find(hdl);
    if (it == clients.end()) return;
    const std::string address = it->second.address;
    clients.erase(it);
    updateSubscribed();
    client_count = clients.size();
    note("client disconnected: " + address + " (" + std::to_string(clients.size()) + " connected)");
  }

  void onMessage(Handle hdl, Server::message_ptr msg) {
    const auto it = clients.find(hdl);
    if (it == clients.end()) return;
    const bool text = msg->get_opcode() == websocketpp::frame::opcode::text;
    const foxglove::ClientSession::Outcome outcome =
        text ? it->second.session.onText(msg->get_payload()) : it->second.session.onBinary(msg->get_payload());
    for (const std::string& reply : outcome.replies) sendText(hdl, reply);
    updateSubscribed();
    record(outcome);
  }

  void onHttp(Handle hdl) {
    Server::connection_ptr con = server.get_con_from_hdl(hdl);
    std::string resource = con->get_resource();
    resource = resource.substr(0, resource.find('?'));
    const auto file = page.find(resource);
    if (file == page.end()) {
      con->set_status(websocketpp::http::status_code::not_found);
      con->set_body("not found\n");
      return;
    }
    con->set_status(websocketpp::http::status_code::ok);
    con->append_header("Content-Type", file->second.type);
    con->append_header("Cache-Control", "no-cache");
    con->set_body(file->second.body);
  }

  void sendText(Handle hdl, const std::string& text) {
    websocketpp::lib::error_code ec;
    server.send(hdl, text, websocketpp::frame::opcode::text, ec);
  }

  /// Hands queued frames to websocketpp while it holds little for that client.
  void flush(Handle hdl, Client& client) {
    Server::connection_ptr con = server.get_con_from_hdl(hdl);
    while (!client.queue.empty() && con->get_buffered_amount() < kMaxSocketBacklog) {
      websocketpp::lib::error_code ec = con->send(client.queue.pop(), websocketpp::frame::opcode::binary);
      if (ec) break;
    }
  }

  void deliver(uint32_t channel_id, uint64_t receive_time_ns, const std::shared_ptr<const std::string>& payload) {
    uint64_t dropped = 0;
    for (auto& [hdl, client] : clients) {
      const std::optional<uint32_t> subscription = client.session.subscriptionFor(channel_id);
      if (!subscription) continue;
      dropped += client.queue.push(foxglove::messageDataFrame(*subscription, receive_time_ns, *payload));
      flush(hdl, client);
    }
    if (dropped == 0) return;
    std::lock_guard lock(events_mutex);
    events.dropped += dropped;
  }

  void scheduleFlush() {
    flush_timer = server.set_timer(kFlushPeriodMs, [this](const websocketpp::lib::error_code& ec) {
      if (ec) return;
      for (auto& [hdl, client] : clients) flush(hdl, client);
      scheduleFlush();
    });
  }

  void run() {
    while (!server.stopped()) {
      try {
        server.run();
      } catch (const std::exception& e) {
        note(std::string("server error: ") + e.what(), "server: internal error");
      }
    }
  }
};

BridgeServer::BridgeServer(ServerOptions options, const foxglove::ChannelTable& channels)
    : impl_(std::make_unique<Impl>(std::move(options), channels, clients_)) {}

BridgeServer::~BridgeServer() { stop(); }

void BridgeServer::start() {
  Impl& s = *impl_;
  s.server.clear_access_channels(websocketpp::log::alevel::all);
  s.server.clear_error_channels(websocketpp::log::elevel::all);
  s.server.init_asio();
  s.server.set_reuse_addr(true);
  s.server.set_validate_handler([&s](Handle h) { return s.validate(h); });
  s.server.set_open_handler([&s](Handle h) { s.onOpen(h); });
  s.server.set_close_handler([&s](Handle h) { s.onClose(h); });
  s.server.set_fail_handler([&s](Handle h) { s.onClose(h); });
  s.server.set_message_handler([&s](Handle h, Server::message_ptr m) { s.onMessage(h, m); });
  s.server.set_http_handler([&s](Handle h) { s.onHttp(h); });
  websocketpp::lib::error_code ec;
  s.server.listen(s.options.bind, std::to_string(s.options.port), ec);
  if (ec) throw std::runtime_error("cannot listen on " + s.options.bind + ":" + std::to_string(s.options.port) + ": " + ec.message());
  s.server.start_accept(ec);
  if (ec) throw std::runtime_error("cannot accept connections: " + ec.message());
  s.scheduleFlush();
  s.thread = std::thread([&s] { s.run(); });
}

void BridgeServer::stop() {
  if (!impl_ || !impl_->thread.joinable()) return;
  impl_->server.stop();
  impl_->thread.join();
}

bool BridgeServer::subscribed(uint32_t channel_id) const {
  std::lock_guard lock(impl_->subscribed_mutex);
  return impl_->subscribed.count(channel_id) > 0;
}

void BridgeServer::broadcast(uint32_t channel_id, uint64_t receive_time_ns, std::string payload) {
  auto shared = std::make_shared<const std::string>(std::move(payload));
  Impl* s = impl_.get();
  asio::post(s->server.get_io_service(), [s, channel_id, receive_time_ns, shared] {
    s->deliver(channel_id, receive_time_ns, shared);
  });
}

ServerEvents BridgeServer::takeEvents() {
  std::lock_guard lock(impl_->events_mutex);
  ServerEvents out = std::move(impl_->events);
  impl_->events = ServerEvents{};
  return out;
}

}  // namespace polarslam
