// The HTTP listener's connections (server/http_listener.cc). httplib gives each connection a
// handler thread while it reads the request, so 17 clients sending a header line every few
// seconds held all 16 threads and /healthz with them. Here one gate thread polls every
// connection until its request head is complete, within one deadline for the whole request, and
// only then hands it to a handler thread; GET /healthz goes to a thread of its own. A request's
// body is read on the handler thread within the same deadline and up to a byte limit, chunked
// bodies included (httplib 0.11 bounds only a Content-Length).
#pragma once

#include <httplib.h>
#include <openssl/ssl.h>
#include <sys/socket.h>

#include <memory>
#include <type_traits>

#include "absl/time/time.h"

namespace lf {

struct HttpGateLimits {
    int handler_threads = 16;
    // From a request's first byte to the last byte of its body.
    absl::Duration request_read_time = absl::Seconds(10);
    // How long a connection may stay open between requests.
    absl::Duration keep_alive = absl::Seconds(1);
    size_t max_head_bytes = 16 << 10;
    size_t max_body_bytes = 64 << 10;
    int max_requests_per_connection = 100;
    // Connections beyond this are closed as they come.
    size_t max_connections = 512;
};

// Answers one request read from `stream` (httplib::Server::process_request).
using HttpExchange =
    std::function<bool(httplib::Stream& stream, bool close_connection, bool& connection_closed)>;

class HttpGate {
  public:
    // `ssl_context`: TLS on every connection; nullptr: plain HTTP.
    HttpGate(HttpGateLimits limits, SSL_CTX* ssl_context, HttpExchange exchange);
    ~HttpGate();  // Stop()
    // Takes a socket just accepted; closes it when done with it.
    void Adopt(int fd);
    // Closes every connection, waits for the answers under way.
    void Stop();

    // For the error handler: whether the request being answered on this thread was cut off
    // because its body was over the limit (413) or not all read within the deadline (408).
    static bool BodyOverLimit();
    static bool ReadTimedOut();

  private:
    struct State;
    std::unique_ptr<State> state_;
};

// An httplib::Server or httplib::SSLServer whose connections go through an HttpGate.
template <class Base>
class GatedServer : public Base {
  public:
    template <class... Args>
    explicit GatedServer(const HttpGateLimits& limits, Args&&... args)
        : Base(std::forward<Args>(args)...),
          gate_(limits, ContextOf(*this),
                [this](httplib::Stream& stream, bool close, bool& closed) {
                    return this->process_request(stream, close, closed, nullptr);
                }) {
        // Accepting is all the listening thread does; the gate reads. httplib listens with a
        // backlog of 5: a burst of connections beyond it (a health probe among them) would wait
        // a second for their SYN to be sent again.
        this->new_task_queue = [this] {
            ::listen(this->svr_sock_, SOMAXCONN);
            return new InlineQueue();
        };
    }
    // Stopped after stop() and the end of listen_after_bind().
    HttpGate& gate() { return gate_; }

  private:
    static SSL_CTX* ContextOf(Base& server) {
        if constexpr (std::is_base_of_v<httplib::SSLServer, Base>) {
            return server.ssl_context();
        } else {
            return nullptr;
        }
    }
    struct InlineQueue : httplib::TaskQueue {
        void enqueue(std::function<void()> fn) override { fn(); }
        void shutdown() override {}
    };
    bool process_and_close_socket(socket_t sock) override {
        gate_.Adopt(sock);
        return true;
    }
    HttpGate gate_;
};

}  // namespace lf
