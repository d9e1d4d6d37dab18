#include "lf/server/health_port.h"

#include <grpcpp/generic/async_generic_service.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>

namespace lf {

absl::StatusOr<HealthPort> StartHealthPort(const std::string& listen) {
    grpc::EnableDefaultHealthCheckService(true);
    grpc::ServerBuilder builder;
    // As the main port: a second server on the port fails instead of sharing it.
    builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
    HealthPort health;
    // gRPC starts a server only with a service of its own besides health: one that answers
    // every other method UNIMPLEMENTED.
    health.others = std::make_unique<grpc::CallbackGenericService>();
    builder.RegisterCallbackGenericService(health.others.get());
    builder.AddListeningPort(listen, grpc::InsecureServerCredentials(), &health.port);
    health.server = builder.BuildAndStart();
    if (!health.server || health.port == 0) {
        return absl::UnavailableError("cannot listen on " + listen +
                                      " for --grpc-health (is the port in use?)");
    }
    return health;
}

}  // namespace lf
