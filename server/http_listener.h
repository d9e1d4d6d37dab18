// lightfarm-server --http: plain HTTP for probes and Prometheus, apart from the gRPC port.
// GET /healthz answers 200 "ok" while the job store is usable (503 and the reason otherwise);
// GET /metrics answers the farm's metrics in Prometheus' text format (docs/farm.md lists them).
// A thin adapter over Farm's queries; the handlers are plain functions, tested without HTTP.
#pragma once

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "server/farm.h"

namespace lf {

struct HttpAnswer {
    int status = 200;
    std::string content_type;
    std::string body;
};

HttpAnswer HealthzAnswer(Farm& farm);
HttpAnswer MetricsAnswer(Farm& farm);

class HttpListener {
  public:
    // Listens on `host_port` (HOST:PORT; port 0 picks a free one) and serves on threads of its
    // own until destroyed. InvalidArgument for an address that is not HOST:PORT;
    // FailedPrecondition "cannot listen on HOST:PORT for --http" when the port cannot be bound.
    static absl::StatusOr<std::unique_ptr<HttpListener>> Start(const std::string& host_port,
                                                               Farm& farm);
    ~HttpListener();  // stops listening and waits for the answers under way

    int port() const { return port_; }

  private:
    struct Server;  // keeps httplib out of the server's other files
    HttpListener(std::unique_ptr<Server> server, int port);
    std::unique_ptr<Server> server_;
    int port_;
};

}  // namespace lf
