// A plain-text gRPC port that serves only grpc.health.v1.Health (lightfarm-server
// --grpc-health), for probes that cannot speak TLS, such as Kubernetes' grpc probe: it tells
// whether the server runs and nothing else, so it needs neither TLS nor a token.
#pragma once

#include <grpcpp/server.h>

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "lf/server/health_service.h"

namespace lf {

struct HealthPort {
    std::unique_ptr<HealthService> health;  // outlives the server
    std::unique_ptr<grpc::Server> server;
    int port = 0;  // the one bound, for HOST:0
};

// Serves SERVING until health->SetServing(false).
// Unavailable naming `listen` when it cannot be bound.
absl::StatusOr<HealthPort> StartHealthPort(const std::string& listen);

}  // namespace lf
