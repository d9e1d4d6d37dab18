#include "lf/proto/grpc_status.h"

#include <string>

#include "absl/time/clock.h"

namespace lf {

// Both enums use the canonical gRPC code numbers.
grpc::Status ToGrpcStatus(const absl::Status& status) {
    if (status.ok()) return grpc::Status::OK;
    return grpc::Status(static_cast<grpc::StatusCode>(status.code()),
                        std::string(status.message()));
}

absl::Status FromGrpcStatus(const grpc::Status& status) {
    if (status.ok()) return absl::OkStatus();
    return absl::Status(static_cast<absl::StatusCode>(status.error_code()), status.error_message());
}

std::unique_ptr<grpc::ClientContext> ContextWithDeadline(absl::Duration timeout) {
    auto context = std::make_unique<grpc::ClientContext>();
    context->set_deadline(absl::ToChronoTime(absl::Now() + timeout));
    return context;
}

}  // namespace lf
