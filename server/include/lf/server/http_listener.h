// lightfarm-server --http: HTTP (HTTPS with the server's certificate) for probes, Prometheus and
// the web dashboard, apart from the gRPC port. GET /healthz answers 200 "ok" while the job store
// is usable (503 and the reason otherwise); GET /metrics answers the farm's metrics in
// Prometheus' text format (docs/farm.md lists them); /, /web/ and /api/ are the dashboard's
// (server/dashboard.h). A thin adapter over Farm's queries; the handlers are plain functions,
// tested without HTTP.
#pragma once

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "lf/server/auth.h"
#include "lf/server/farm.h"
#include "lf/server/http_exchange.h"

namespace lf {

HttpAnswer HealthzAnswer(Farm& farm);
HttpAnswer MetricsAnswer(Farm& farm);

struct HttpListenerOptions {
    // The dashboard's callers are authenticated by this; nullptr: no dashboard.
    Authenticator* dashboard_auth = nullptr;
    // PEM files: HTTPS with them when both are set (the gRPC port's --tls-cert and --tls-key).
    std::string tls_cert, tls_key;
    // From a request's first byte to the end of its body: a client slower than this is cut off
    // (408), however steadily it sends.
    absl::Duration request_read_time = absl::Seconds(10);
};

class HttpListener {
  public:
    // Listens on `host_port` (HOST:PORT; port 0 picks a free one) and serves on threads of its
    // own until destroyed. InvalidArgument for an address that is not HOST:PORT;
    // FailedPrecondition "cannot listen on HOST:PORT for --http" when the port cannot be bound,
    // or the TLS files cannot be used.
    static absl::StatusOr<std::unique_ptr<HttpListener>> Start(
        const std::string& host_port, Farm& farm, const HttpListenerOptions& options = {});
    ~HttpListener();  // stops listening and waits for the answers under way

    int port() const { return port_; }

  private:
    struct Server;  // keeps httplib out of the server's other files
    HttpListener(std::unique_ptr<Server> server, int port);
    std::unique_ptr<Server> server_;
    int port_;
};

}  // namespace lf
