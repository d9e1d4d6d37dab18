// A TCP proxy on loopback for tests of dropped connections: it forwards to a server's port,
// counts the bytes a connection sends through it, and can cut a connection (close both ends) once
// that connection has carried a given number of bytes towards the server, as a network that fails
// halfway through an upload would.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace lf::testing {

class CuttingProxy {
  public:
    explicit CuttingProxy(int target_port) : target_port_(target_port) {
        listener_ = ::socket(AF_INET, SOCK_STREAM, 0);
        sockaddr_in addr = Loopback(0);
        ::bind(listener_, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
        ::listen(listener_, 16);
        socklen_t len = sizeof addr;
        ::getsockname(listener_, reinterpret_cast<sockaddr*>(&addr), &len);
        port_ = ntohs(addr.sin_port);
        acceptor_ = std::thread([this] { Accept(); });
    }
    ~CuttingProxy() {
        stop_ = true;
        acceptor_.join();
        std::lock_guard<std::mutex> lock(mutex_);
        for (std::thread& t : pumps_) t.join();
        ::close(listener_);
    }
    CuttingProxy(const CuttingProxy&) = delete;
    CuttingProxy& operator=(const CuttingProxy&) = delete;

    int port() const { return port_; }
    // The next connection made is cut once it has carried `bytes` towards the server; later
    // ones are not.
    void CutNextAfter(uint64_t bytes) { cut_next_after_ = bytes; }
    // Bytes the connection made last sent towards the server.
    uint64_t bytes_of_last_connection() const {
        std::lock_guard<std::mutex> lock(mutex_);
        return last_connection_bytes_;
    }
    int connections_cut() const { return cuts_; }

  private:
    static sockaddr_in Loopback(int port) {
        sockaddr_in addr{};
        addr.sin_family = AF_INET;
        addr.sin_port = htons(uint16_t(port));
        addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        return addr;
    }

    void Accept() {
        while (!stop_) {
            pollfd p{listener_, POLLIN, 0};
            if (::poll(&p, 1, 50) <= 0) continue;
            const int client = ::accept(listener_, nullptr, nullptr);
            if (client < 0) continue;
            const int server = ::socket(AF_INET, SOCK_STREAM, 0);
            sockaddr_in addr = Loopback(target_port_);
            if (::connect(server, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
                ::close(client);
                ::close(server);
                continue;
            }
            const uint64_t cut_after = cut_next_after_.exchange(0);
            std::lock_guard<std::mutex> lock(mutex_);
            last_connection_bytes_ = 0;
            const int index = int(pumps_.size());
            pumps_.emplace_back([this, client, server, cut_after, index] {
                Pump(client, server, cut_after, index);
            });
        }
    }

    // Forwards both ways until either end closes, the cut, or the proxy stops.
    // `index`: the connection's place in the order they were made.
    void Pump(int client, int server, uint64_t cut_after, int index) {
        uint64_t carried = 0;
        std::vector<char> buffer(1 << 16);
        while (!stop_) {
            pollfd p[2] = {{client, POLLIN, 0}, {server, POLLIN, 0}};
            if (::poll(p, 2, 50) <= 0) continue;
            bool closed = false;
            for (int i = 0; i < 2 && !closed; ++i) {
                if (!(p[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
                const ssize_t n = ::read(p[i].fd, buffer.data(), buffer.size());
                if (n <= 0) {
                    closed = true;
                    break;
                }
                const int to = i == 0 ? server : client;
                for (ssize_t sent = 0; sent < n;) {
                    // Not write(): a peer gone would raise SIGPIPE in the test.
                    const ssize_t w =
                        ::send(to, buffer.data() + sent, size_t(n - sent), MSG_NOSIGNAL);
                    if (w <= 0) {
                        closed = true;
                        break;
                    }
                    sent += w;
                }
                if (i == 0) {
                    carried += uint64_t(n);
                    {
                        std::lock_guard<std::mutex> lock(mutex_);
                        if (index + 1 == int(pumps_.size())) last_connection_bytes_ = carried;
                    }
                    if (cut_after > 0 && carried >= cut_after) {
                        ++cuts_;
                        closed = true;
                    }
                }
            }
            if (closed) break;
        }
        ::close(client);
        ::close(server);
    }

    const int target_port_;
    int listener_ = -1;
    int port_ = 0;
    std::atomic<bool> stop_{false};
    std::atomic<uint64_t> cut_next_after_{0};
    std::atomic<int> cuts_{0};
    std::thread acceptor_;
    mutable std::mutex mutex_;
    std::vector<std::thread> pumps_;  // one per connection, in the order they were made
    uint64_t last_connection_bytes_ = 0;
};

}  // namespace lf::testing
