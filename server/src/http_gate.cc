#include "http_gate.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <openssl/err.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <csignal>
#include <mutex>
#include <thread>
#include <unordered_set>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "lf/core/log.h"

namespace lf {

namespace {

std::shared_ptr<spdlog::logger> Log() { return NamedLogger("http"); }

constexpr absl::Duration kWriteTime = absl::Seconds(5);
// Chunk sizes and line ends on top of a chunked body at the limit.
constexpr size_t kChunkFramingBytes = 8 << 10;
// After a refused body the rest is read and dropped for a while: closing with unread bytes
// would reset the connection, and the client could lose the answer.
constexpr absl::Duration kLingerTime = absl::Seconds(2);
constexpr size_t kLingerBytes = 1 << 20;

std::string AddressOf(int fd, bool peer, int* port) {
    sockaddr_storage address{};
    socklen_t size = sizeof address;
    auto* a = reinterpret_cast<sockaddr*>(&address);
    if ((peer ? getpeername(fd, a, &size) : getsockname(fd, a, &size)) != 0) return "?";
    char text[INET6_ADDRSTRLEN] = "?";
    if (address.ss_family == AF_INET) {
        auto* v4 = reinterpret_cast<sockaddr_in*>(&address);
        inet_ntop(AF_INET, &v4->sin_addr, text, sizeof text);
        *port = ntohs(v4->sin_port);
    } else if (address.ss_family == AF_INET6) {
        auto* v6 = reinterpret_cast<sockaddr_in6*>(&address);
        inet_ntop(AF_INET6, &v6->sin6_addr, text, sizeof text);
        *port = ntohs(v6->sin6_port);
    }
    return text;
}

// Waits until `fd` is ready for `events` or `until` passes (false then).
bool WaitFor(int fd, short events, absl::Time until) {
    while (true) {
        const int64_t ms =
            absl::ToInt64Milliseconds(absl::Ceil(until - absl::Now(), absl::Milliseconds(1)));
        if (ms <= 0) return false;
        pollfd p{fd, events, 0};
        const int r = poll(&p, 1, int(std::min<int64_t>(ms, INT_MAX)));
        if (r > 0) return true;
        if (r < 0 && errno != EINTR) return false;
    }
}

// One client's connection, TLS or not, on a non-blocking socket.
class Connection {
  public:
    Connection(int fd, SSL* ssl) : fd_(fd), ssl_(ssl) {
        int port = 0;
        peer = AddressOf(fd, true, &port);
        peer = absl::StrCat(peer, ":", port);
    }
    ~Connection() {
        if (ssl_) {
            if (!failed_ && SSL_is_init_finished(ssl_)) SSL_shutdown(ssl_);
            SSL_free(ssl_);
        }
        ::close(fd_);
    }
    int fd() const { return fd_; }
    bool tls() const { return ssl_ != nullptr; }

    // > 0: bytes moved; 0: closed or failed; -1: nothing now, wait for `*wait`.
    ssize_t Read(char* to, size_t n, short* wait) {
        if (ssl_) {
            ERR_clear_error();
            return SslResult(SSL_read(ssl_, to, int(std::min<size_t>(n, INT_MAX))), wait);
        }
        return PlainResult(::recv(fd_, to, n, 0), POLLIN, wait);
    }
    ssize_t Write(const char* from, size_t n, short* wait) {
        if (ssl_) {
            ERR_clear_error();
            return SslResult(SSL_write(ssl_, from, int(std::min<size_t>(n, INT_MAX))), wait);
        }
        return PlainResult(::send(fd_, from, n, MSG_NOSIGNAL), POLLOUT, wait);
    }

    std::string peer;   // IP:port, for logs
    std::string ahead;  // bytes read and not yet parsed: the head, and what followed it
    size_t head_bytes = 0;
    absl::Time started = absl::InfinitePast();  // the request's first byte (or accept)
    absl::Time idle_until;                      // before `started`: when to close it
    int served = 0;

  private:
    ssize_t PlainResult(ssize_t r, short event, short* wait) {
        if (r >= 0) return r;
        if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) {
            *wait = event;
            return -1;
        }
        return 0;
    }
    ssize_t SslResult(int r, short* wait) {
        if (r > 0) return r;
        switch (SSL_get_error(ssl_, r)) {
            case SSL_ERROR_WANT_READ:
                *wait = POLLIN;
                return -1;
            case SSL_ERROR_WANT_WRITE:
                *wait = POLLOUT;
                return -1;
            case SSL_ERROR_ZERO_RETURN:
                return 0;
            default:
                failed_ = true;
                return 0;
        }
    }
    int fd_;
    SSL* ssl_;
    bool failed_ = false;
};

// A request as httplib reads it: the head the gate read, then the socket, within the request's
// deadline and up to its byte limit.
class GateStream final : public httplib::Stream {
  public:
    GateStream(Connection& c, absl::Time deadline, size_t max_bytes)
        : c_(c), ahead_(std::move(c.ahead)), deadline_(deadline), max_bytes_(max_bytes) {}

    bool is_readable() const override {
        return pos_ < ahead_.size() || WaitFor(c_.fd(), POLLIN, deadline_);
    }
    bool is_writable() const override {
        return WaitFor(c_.fd(), POLLOUT, absl::Now() + kWriteTime);
    }
    ssize_t read(char* ptr, size_t size) override {
        if (pos_ < ahead_.size()) {
            const size_t n = std::min(size, ahead_.size() - pos_);
            std::copy_n(ahead_.data() + pos_, n, ptr);
            pos_ += n;
            consumed_ += n;
            return ssize_t(n);
        }
        if (consumed_ >= max_bytes_) {
            over_limit_ = true;
            return -1;
        }
        size = std::min(size, max_bytes_ - consumed_);
        while (true) {
            short wait = POLLIN;
            const ssize_t n = c_.Read(ptr, size, &wait);
            if (n >= 0) {
                consumed_ += size_t(n);
                return n;
            }
            if (!WaitFor(c_.fd(), wait, deadline_)) {
                timed_out_ = true;
                return -1;
            }
        }
    }
    ssize_t write(const char* ptr, size_t size) override {
        const absl::Time until = absl::Now() + kWriteTime;
        size_t done = 0;
        while (done < size) {
            short wait = POLLOUT;
            const ssize_t n = c_.Write(ptr + done, size - done, &wait);
            if (n > 0) {
                done += size_t(n);
            } else if (n == 0 || !WaitFor(c_.fd(), wait, until)) {
                return -1;
            }
        }
        return ssize_t(size);
    }
    void get_remote_ip_and_port(std::string& ip, int& port) const override {
        ip = AddressOf(c_.fd(), true, &port);
    }
    void get_local_ip_and_port(std::string& ip, int& port) const override {
        ip = AddressOf(c_.fd(), false, &port);
    }
    socket_t socket() const override { return c_.fd(); }

    bool over_limit() const { return over_limit_; }
    bool timed_out() const { return timed_out_; }
    // What the client sent after this request (pipelined).
    std::string Rest() const { return ahead_.substr(pos_); }

  private:
    Connection& c_;
    std::string ahead_;
    size_t pos_ = 0;
    absl::Time deadline_;
    size_t max_bytes_;
    size_t consumed_ = 0;
    bool over_limit_ = false, timed_out_ = false;
};

thread_local const GateStream* t_stream = nullptr;

// The end of the request head in `text`, searching from `from`; npos while incomplete.
size_t HeadEnd(const std::string& text, size_t from) {
    const size_t at = text.find("\r\n\r\n", from >= 3 ? from - 3 : 0);
    return at == std::string::npos ? at : at + 4;
}

// GET or HEAD /healthz, with or without a query, and without a body: one sent slowly would hold
// the health thread.
bool IsHealthProbe(std::string_view head) {
    const size_t space = head.find(' ');
    if (space == std::string_view::npos) return false;
    const std::string_view method = head.substr(0, space);
    std::string_view target = head.substr(space + 1);
    target = target.substr(0, std::min(target.find(' '), target.find('?')));
    const std::string lower = absl::AsciiStrToLower(std::string(head));
    return (method == "GET" || method == "HEAD") && target == "/healthz" &&
           !absl::StrContains(lower, "\ncontent-length:") &&
           !absl::StrContains(lower, "\ntransfer-encoding:");
}

}  // namespace

bool HttpGate::BodyOverLimit() { return t_stream && t_stream->over_limit(); }
bool HttpGate::ReadTimedOut() { return t_stream && t_stream->timed_out(); }

struct HttpGate::State {
    HttpGateLimits limits;
    SSL_CTX* ssl_context;
    HttpExchange exchange;
    int wake_fd = -1;
    std::mutex mutex;                                // what follows
    std::vector<std::shared_ptr<Connection>> inbox;  // for the gate thread
    std::unordered_set<Connection*> open;
    bool stopping = false;
    httplib::ThreadPool handlers, health;
    std::thread thread;

    State(HttpGateLimits l, SSL_CTX* context, HttpExchange e)
        : limits(l),
          ssl_context(context),
          exchange(std::move(e)),
          wake_fd(eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)),
          handlers(size_t(l.handler_threads)),
          health(1) {}

    void Wake() {
        const uint64_t one = 1;
        [[maybe_unused]] ssize_t w = ::write(wake_fd, &one, sizeof one);
    }
    void Queue(std::shared_ptr<Connection> c) {
        {
            std::lock_guard<std::mutex> lock(mutex);
            if (stopping) return;
            inbox.push_back(std::move(c));
        }
        Wake();
    }

    // Tells a client its request was refused, if its socket takes it now.
    static void Refuse(Connection& c, int status, const char* reason) {
        const std::string answer = absl::StrCat(
            "HTTP/1.1 ", status, " ", reason, "\r\nConnection: close\r\nContent-Length: 0\r\n\r\n");
        short wait = 0;
        c.Write(answer.data(), answer.size(), &wait);
    }

    // Reads what `c` has sent. True while it should wait for `*wait`; false once it is handed
    // on or dropped.
    bool Advance(const std::shared_ptr<Connection>& c, short* wait) {
        size_t searched = 0;
        while (true) {
            if (const size_t end = HeadEnd(c->ahead, searched); end != std::string::npos) {
                c->head_bytes = end;
                httplib::ThreadPool& pool = IsHealthProbe(c->ahead) ? health : handlers;
                pool.enqueue([this, c] { Serve(c); });
                return false;
            }
            searched = c->ahead.size();
            if (searched >= limits.max_head_bytes) {
                Log()->info("closed the connection from {}: a request head over {} bytes", c->peer,
                            limits.max_head_bytes);
                Refuse(*c, 431, "Request Header Fields Too Large");
                return false;
            }
            char buffer[4096];
            const size_t want = std::min(sizeof buffer, limits.max_head_bytes - searched);
            const ssize_t n = c->Read(buffer, want, wait);
            if (n == 0) return false;
            if (n < 0) return true;
            if (c->started == absl::InfinitePast()) c->started = absl::Now();
            c->ahead.append(buffer, size_t(n));
        }
    }

    absl::Time DeadlineOf(const Connection& c) const {
        return c.started == absl::InfinitePast() ? c.idle_until
                                                 : c.started + limits.request_read_time;
    }

    void Run() {
        struct Waiting {
            std::shared_ptr<Connection> c;
            short events;
        };
        std::vector<Waiting> waiting;
        std::vector<pollfd> polled;
        while (true) {
            std::vector<std::shared_ptr<Connection>> arrived;
            {
                std::lock_guard<std::mutex> lock(mutex);
                if (stopping) return;
                arrived.swap(inbox);
            }
            for (std::shared_ptr<Connection>& c : arrived) {
                short wait = POLLIN;
                if (Advance(c, &wait)) waiting.push_back({std::move(c), wait});
            }
            const absl::Time now = absl::Now();
            std::vector<Waiting> kept;
            for (Waiting& w : waiting) {
                if (now < DeadlineOf(*w.c)) {
                    kept.push_back(std::move(w));
                } else if (w.c->started != absl::InfinitePast()) {
                    Log()->info("closed the connection from {}: no complete request within {}",
                                w.c->peer, absl::FormatDuration(limits.request_read_time));
                    Refuse(*w.c, 408, "Request Timeout");
                }
            }
            waiting.swap(kept);
            absl::Time next = now + absl::Seconds(1);
            polled.assign(1, pollfd{wake_fd, POLLIN, 0});
            for (const Waiting& w : waiting) {
                polled.push_back({w.c->fd(), w.events, 0});
                next = std::min(next, DeadlineOf(*w.c));
            }
            const int64_t ms =
                absl::ToInt64Milliseconds(absl::Ceil(next - now, absl::Milliseconds(1)));
            if (poll(polled.data(), polled.size(), int(std::max<int64_t>(ms, 0))) < 0 &&
                errno != EINTR) {
                Log()->error("poll failed: {}", strerror(errno));
            }
            if (polled[0].revents) {
                uint64_t count = 0;
                [[maybe_unused]] ssize_t r = ::read(wake_fd, &count, sizeof count);
            }
            kept.clear();
            for (size_t i = 0; i < waiting.size(); ++i) {
                Waiting& w = waiting[i];
                if (polled[i + 1].revents == 0 || Advance(w.c, &w.events)) {
                    kept.push_back(std::move(w));
                }
            }
            waiting.swap(kept);
        }
    }

    // On a handler thread: answers the request `c` holds, then gives `c` back to the gate for
    // its next one.
    void Serve(const std::shared_ptr<Connection>& c) {
        const bool last = ++c->served >= limits.max_requests_per_connection;
        GateStream stream(*c, c->started + limits.request_read_time,
                          c->head_bytes + limits.max_body_bytes + kChunkFramingBytes);
        bool closed = false;
        t_stream = &stream;
        const bool answered = exchange(stream, last, closed);
        t_stream = nullptr;
        if (stream.over_limit()) {
            Log()->info("refused a request body over {} bytes from {}", limits.max_body_bytes,
                        c->peer);
            Linger(*c);
            return;
        }
        if (!answered || closed || last || stream.timed_out()) return;
        c->ahead = stream.Rest();
        c->started = c->ahead.empty() ? absl::InfinitePast() : absl::Now();
        c->idle_until = absl::Now() + limits.keep_alive;
        Queue(c);
    }

    // Ends the answer and drops what the client still sends, for a while.
    static void Linger(Connection& c) {
        if (!c.tls()) ::shutdown(c.fd(), SHUT_WR);
        const absl::Time until = absl::Now() + kLingerTime;
        char buffer[16 << 10];
        for (size_t dropped = 0; dropped < kLingerBytes;) {
            short wait = POLLIN;
            const ssize_t n = c.Read(buffer, sizeof buffer, &wait);
            if (n == 0) return;
            if (n > 0) {
                dropped += size_t(n);
            } else if (!WaitFor(c.fd(), wait, until)) {
                return;
            }
        }
    }
};

HttpGate::HttpGate(HttpGateLimits limits, SSL_CTX* ssl_context, HttpExchange exchange)
    : state_(std::make_unique<State>(limits, ssl_context, std::move(exchange))) {
    // A write to a client that has gone must fail, not end the server (SSL_write cannot be told).
    std::signal(SIGPIPE, SIG_IGN);
    state_->thread = std::thread([s = state_.get()] { s->Run(); });
}

HttpGate::~HttpGate() { Stop(); }

void HttpGate::Adopt(int fd) {
    State& s = *state_;
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
    std::shared_ptr<Connection> c;
    {
        std::lock_guard<std::mutex> lock(s.mutex);
        if (s.stopping || s.open.size() >= s.limits.max_connections) {
            if (!s.stopping) {
                Log()->warn("refused a connection: {} are open already", s.open.size());
            }
            ::close(fd);
            return;
        }
        SSL* ssl = nullptr;
        if (s.ssl_context) {
            ssl = SSL_new(s.ssl_context);
            SSL_set_fd(ssl, fd);
            SSL_set_accept_state(ssl);
        }
        c = std::shared_ptr<Connection>(new Connection(fd, ssl), [&s](Connection* gone) {
            {
                std::lock_guard<std::mutex> lock(s.mutex);
                s.open.erase(gone);
            }
            delete gone;
        });
        s.open.insert(c.get());
    }
    // The TLS handshake counts as part of the first request.
    c->started = absl::Now();
    s.Queue(std::move(c));
}

void HttpGate::Stop() {
    State& s = *state_;
    {
        std::lock_guard<std::mutex> lock(s.mutex);
        if (s.stopping) return;
        s.stopping = true;
        // Reads under way fail at once.
        for (Connection* c : s.open) ::shutdown(c->fd(), SHUT_RDWR);
    }
    s.Wake();
    s.thread.join();
    s.inbox.clear();
    s.handlers.shutdown();
    s.health.shutdown();
    ::close(s.wake_fd);
}

}  // namespace lf
