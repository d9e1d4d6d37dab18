#include "lf/server/health_port.h"

#include <grpcpp/grpcpp.h>

namespace lf {

absl::StatusOr<HealthPort> StartHealthPort(const std::string& listen) {
    grpc::ServerBuilder builder;
    // As the main port: a second server on the port fails instead of sharing it.
    builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
    HealthPort health;
    health.health = std::make_unique<HealthService>();
    builder.RegisterService(health.health.get());
    builder.AddListeningPort(listen, grpc::InsecureServerCredentials(), &health.port);
    health.server = builder.BuildAndStart();
    if (!health.server || health.port == 0) {
        return absl::UnavailableError("cannot listen on " + listen +
                                      " for --grpc-health (is the port in use?)");
    }
    return health;
}

}  // namespace lf
