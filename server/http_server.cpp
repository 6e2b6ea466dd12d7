#include "server/http_server.hpp"

#include <spdlog/spdlog.h>

#include <boost/asio.hpp>
#include <boost/beast.hpp>
#include <atomic>
#include <chrono>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <string>

#include "server/json_codec.hpp"
#include "server/thread_priority.hpp"

namespace corridor::server {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

namespace {

double wall_clock_s() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

class WsSession;

// Fan-out of events to stream clients: weak pointers copied under the lock, sent after it.
class EventHub {
 public:
  void join(const std::shared_ptr<WsSession>& s) {
    std::lock_guard lock(mutex_);
    sessions_.push_back(s);
  }
  void publish(const std::string& text, MissionId mission);
  // Lets the publisher skip rendering an event that nobody would receive.
  [[nodiscard]] bool empty() {
    std::lock_guard lock(mutex_);
    return sessions_.empty();
  }

 private:
  std::mutex mutex_;
  std::vector<std::weak_ptr<WsSession>> sessions_;
};

class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(tcp::socket&& socket, EventHub& hub, std::optional<MissionId> filter, std::size_t max_queue)
      : ws_(std::move(socket)), hub_(hub), filter_(filter), max_queue_(max_queue) {}

  void run(http::request<http::string_body> req) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.async_accept(req, beast::bind_front_handler(&WsSession::on_accept, shared_from_this()));
  }

  void send(std::shared_ptr<const std::string> text, MissionId mission) {
    if (filter_ && mission != 0 && mission != *filter_) return;
    if (filter_ && mission == 0) return;  // a mission subscription gets only that mission's events
    net::post(ws_.get_executor(), [self = shared_from_this(), text] { self->queue(text); });
  }

 private:
  void on_accept(beast::error_code ec) {
    if (ec) return;
    hub_.join(shared_from_this());
    auto hello = std::make_shared<const std::string>(R"({"type":"hello"})");
    queue(hello);
    read();
  }
  void read() { ws_.async_read(in_, beast::bind_front_handler(&WsSession::on_read, shared_from_this())); }
  void on_read(beast::error_code ec, std::size_t) {
    if (ec) return;  // closed: the hub forgets expired sessions
    in_.consume(in_.size());
    read();
  }
  void queue(std::shared_ptr<const std::string> text) {
    if (closed_) return;
    if (out_.size() >= max_queue_) {
      // A client that cannot keep up is dropped rather than buffered without bound.
      closed_ = true;
      ws_.async_close(websocket::close_code::policy_error, [self = shared_from_this()](beast::error_code) {});
      return;
    }
    out_.push_back(std::move(text));
    if (out_.size() == 1) write();
  }
  void write() {
    ws_.text(true);
    ws_.async_write(net::buffer(*out_.front()), beast::bind_front_handler(&WsSession::on_write, shared_from_this()));
  }
  void on_write(beast::error_code ec, std::size_t) {
    if (ec) {
      closed_ = true;
      return;
    }
    out_.pop_front();
    if (!out_.empty()) write();  // one outstanding async_write at a time
  }

  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer in_;
  std::deque<std::shared_ptr<const std::string>> out_;
  EventHub& hub_;
  std::optional<MissionId> filter_;
  std::size_t max_queue_;
  bool closed_ = false;
};

void EventHub::publish(const std::string& text, MissionId mission) {
  std::vector<std::shared_ptr<WsSession>> live;
  {
    std::lock_guard lock(mutex_);
    std::erase_if(sessions_, [](const auto& w) { return w.expired(); });
    for (const auto& w : sessions_) {
      if (auto s = w.lock()) live.push_back(std::move(s));
    }
  }
  auto shared = std::make_shared<const std::string>(text);
  for (const auto& s : live) s->send(shared, mission);
}

class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket&& socket, Router& router, EventHub& hub, const ServerLimits& limits, net::thread_pool& workers)
      : stream_(std::move(socket)), router_(router), hub_(hub), limits_(limits), workers_(workers) {}

  void run() { net::dispatch(stream_.get_executor(), beast::bind_front_handler(&HttpSession::read, shared_from_this())); }

 private:
  void read() {
    parser_.emplace();
    parser_->body_limit(limits_.body_limit_bytes);
    parser_->header_limit(static_cast<std::uint32_t>(limits_.header_limit_bytes));
    stream_.expires_after(std::chrono::seconds(limits_.read_timeout_s));
    http::async_read(stream_, buffer_, *parser_, beast::bind_front_handler(&HttpSession::on_read, shared_from_this()));
  }

  void on_read(beast::error_code ec, std::size_t) {
    if (ec == http::error::end_of_stream || ec == beast::error::timeout) return close();
    if (ec == http::error::body_limit) return reply_error(413, "payload_too_large", "request body exceeds the limit", false);
    if (ec == http::error::header_limit) return reply_error(431, "headers_too_large", "request headers exceed the limit", false);
    if (ec) return reply_error(400, "bad_request", "malformed HTTP request", false);
    auto req = parser_->release();
    const std::string target(req.target());
    if (websocket::is_upgrade(req)) {
      if (target.rfind("/v1/stream", 0) != 0) return reply_error(404, "not_found", "WebSocket is served on /v1/stream", false);
      if (!router_.authorize_stream(std::string(req[http::field::authorization]), target)) {
        return reply_error(401, "unauthorized",
                           "a viewer or dispatcher token, or a fresh ticket from POST /v1/stream/ticket, is required for the stream",
                           false);
      }
      std::optional<MissionId> filter;
      if (const auto q = target.find("mission="); q != std::string::npos) {
        try {
          filter = std::stoull(target.substr(q + 8));
        } catch (const std::exception&) {
          return reply_error(400, "bad_request", "mission must be a mission id", false);
        }
      }
      stream_.expires_never();
      std::make_shared<WsSession>(stream_.release_socket(), hub_, filter, limits_.max_queued_events)->run(std::move(req));
      return;
    }
    // The answer may come from the commit thread once the request's writes are durable, or from a
    // worker; it is written on this connection's own io_context.
    HttpRequest request{std::string(req.method_string()), target, std::string(req[http::field::authorization]),
                        std::move(req.body())};
    const bool head = req.method() == http::verb::head;
    auto reply = [self = shared_from_this(), keep_alive = req.keep_alive(), head](HttpResponse r) {
      net::dispatch(self->stream_.get_executor(), [self, keep_alive, head, r = std::move(r)]() mutable {
        self->respond(r.status, r.content_type, std::move(r.body), keep_alive, r.headers, head);
      });
    };
    if (!router_.blocks(request)) return router_.handle_async(request, std::move(reply));
    // Waits for storage or plans a route: on a worker, so that this I/O thread goes on serving
    // other connections' position reports meanwhile.
    net::post(workers_, [&router = router_, request = std::move(request), reply = std::move(reply)]() mutable {
      router.handle_async(request, std::move(reply));
    });
  }

  void reply_error(int status, const std::string& code, const std::string& message, bool keep_alive) {
    respond(status, "application/json", error_json(code, message).dump(), keep_alive);
  }

  void respond(int status, const std::string& content_type, std::string body, bool keep_alive,
               const std::vector<std::pair<std::string, std::string>>& headers = {}, bool head = false) {
    auto res = std::make_shared<http::response<http::string_body>>(static_cast<http::status>(status), 11);
    res->set(http::field::server, "corridor");
    res->set(http::field::content_type, content_type);
    for (const auto& [name, value] : headers) res->set(name, value);
    res->keep_alive(keep_alive);
    if (head) {
      // HEAD: the headers GET would send, Content-Length included, and no body.
      res->content_length(body.size());
    } else {
      res->body() = std::move(body);
      res->prepare_payload();
    }
    response_ = res;
    http::async_write(stream_, *res, beast::bind_front_handler(&HttpSession::on_write, shared_from_this(), keep_alive));
  }

  void on_write(bool keep_alive, beast::error_code ec, std::size_t) {
    response_.reset();
    if (ec || !keep_alive) return close();
    read();
  }

  void close() {
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
  }

  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  std::shared_ptr<http::response<http::string_body>> response_;
  Router& router_;
  EventHub& hub_;
  const ServerLimits& limits_;
  net::thread_pool& workers_;
};

ServerLimits checked(ServerLimits limits) {
  if (limits.io_nice < 0 || limits.io_nice > 19) {
    throw std::invalid_argument("io_nice must be 0..19, not " + std::to_string(limits.io_nice));
  }
  return limits;
}

}  // namespace

struct HttpServer::Impl {
  Impl(Router& r, DispatchService& s, ServerLimits l, int n)
      : router(r), service(s), limits(l), shards(make_shards(std::max(1, n))), ioc(*shards.front()),
        acceptor(ioc), signals(ioc, SIGINT, SIGTERM), ticker(ioc), accept_retry(ioc) {
    for (auto& shard : shards) keep_running.push_back(net::make_work_guard(*shard));
  }

  // One io_context per I/O thread, each connection on one of them for its whole life: a
  // connection's handlers then never run concurrently, which is what a strand would give, without
  // the threads contending for one scheduler's lock on every completion.
  static std::vector<std::unique_ptr<net::io_context>> make_shards(int n) {
    std::vector<std::unique_ptr<net::io_context>> out;
    for (int i = 0; i < n; ++i) out.push_back(std::make_unique<net::io_context>(1));
    return out;
  }
  net::io_context& next_shard() { return *shards[next++ % shards.size()]; }

  void accept() {
    acceptor.async_accept(next_shard(), [this](beast::error_code ec, tcp::socket socket) {
      if (!acceptor.is_open() || ec == net::error::operation_aborted) return;  // stopping
      if (!ec) {
        std::make_shared<HttpSession>(std::move(socket), router, hub, limits, workers)->run();
        accept();
        return;
      }
      // Out of file descriptors and the like: back off instead of spinning a core.
      spdlog::warn("event=accept_failed error=\"{}\"", ec.message());
      accept_retry.expires_after(std::chrono::milliseconds(100));
      accept_retry.async_wait([this](beast::error_code wait_ec) {
        if (!wait_ec) accept();
      });
    });
  }
  void tick() {
    ticker.expires_after(std::chrono::seconds(1));
    ticker.async_wait([this](beast::error_code ec) {
      if (ec) return;
      // Expiries replan missions and store their writes: a worker's job, like a congestion report.
      // A tick still running (a large expiry batch) is not joined by another: ticks must not take
      // both workers from the requests.
      if (!ticking.exchange(true)) {
        net::post(workers, [this] {
          try {
            service.tick(wall_clock_s());
          } catch (const std::exception& e) {
            spdlog::error("event=tick_failed error=\"{}\"", e.what());
          }
          ticking = false;
        });
      }
      tick();
    });
  }

  Router& router;
  DispatchService& service;
  ServerLimits limits;
  std::vector<std::unique_ptr<net::io_context>> shards;
  net::io_context& ioc;  // the first shard; it also accepts, ticks and takes signals
  std::vector<net::executor_work_guard<net::io_context::executor_type>> keep_running;
  std::size_t next = 0;  // the shard of the next accepted connection (only the accept handler uses it)
  tcp::acceptor acceptor;
  net::signal_set signals;
  net::steady_timer ticker;
  net::steady_timer accept_retry;
  EventHub hub;
  std::size_t subscription = 0;
  // Runs the requests that block (Router::blocks) and the ticks. Two, so that a mission can be
  // created while a congestion batch is repaired; the service serializes what must be serial.
  net::thread_pool workers{2};
  std::atomic<bool> ticking{false};
};

HttpServer::HttpServer(Router& router, DispatchService& service, ServerLimits limits, const std::string& address,
                       unsigned short port, int threads)
    : impl_(std::make_unique<Impl>(router, service, checked(limits), threads)) {
  const tcp::endpoint endpoint{net::ip::make_address(address), port};
  impl_->acceptor.open(endpoint.protocol());
  impl_->acceptor.set_option(net::socket_base::reuse_address(true));
  impl_->acceptor.bind(endpoint);
  impl_->acceptor.listen(net::socket_base::max_listen_connections);
  impl_->subscription =
      service.subscribe([hub = &impl_->hub](const DispatchEvent& e) {
        if (!hub->empty()) hub->publish(event_to_json(e).dump(), e.mission);
      });
}

HttpServer::~HttpServer() {
  stop();
  // Requests already handed to a worker finish (their writes are stored; the answer has no
  // connection left to go to), and no tick runs after this.
  impl_->workers.join();
  // Answers still waiting for their commit hand their response to a session's executor: let them
  // do that while the io_context is still alive (stopped, it only queues and then drops them).
  try {
    impl_->service.flush();
  } catch (const std::exception& e) {
    spdlog::error("event=flush_failed error=\"{}\"", e.what());
  }
  impl_->service.unsubscribe(impl_->subscription);  // the hub dies with this server
}

unsigned short HttpServer::port() const { return impl_->acceptor.local_endpoint().port(); }

void HttpServer::run() {
  impl_->accept();
  impl_->tick();
  impl_->signals.async_wait([this](beast::error_code, int) { stop(); });
  std::vector<std::thread> pool;
  for (std::size_t i = 0; i < impl_->shards.size(); ++i) {
    pool.emplace_back([this, i] {
      if (!lower_thread_priority(impl_->limits.io_nice)) {
        spdlog::warn("event=io_nice_denied io_nice={} hint=\"the I/O threads run at the process's priority\"", impl_->limits.io_nice);
      }
      impl_->shards[i]->run();
    });
  }
  for (auto& t : pool) t.join();
}

void HttpServer::stop() {
  if (!impl_) return;
  net::post(impl_->ioc, [impl = impl_.get()] {
    beast::error_code ec;
    impl->acceptor.close(ec);
    impl->ticker.cancel();
    impl->accept_retry.cancel();
    impl->signals.cancel();
  });
  for (auto& shard : impl_->shards) shard->stop();
}

}  // namespace corridor::server
