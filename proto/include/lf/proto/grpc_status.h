// Where our modules (absl::Status) meet the wire (gRPC), for every side of it. Status codes map
// one to one and the message travels unchanged, so users see the server's own words.
#pragma once

#include <grpcpp/client_context.h>
#include <grpcpp/support/status.h>

#include <memory>

#include "absl/status/status.h"
#include "absl/time/time.h"

namespace lf {

grpc::Status ToGrpcStatus(const absl::Status& status);
absl::Status FromGrpcStatus(const grpc::Status& status);

// Every client call gets a deadline: a call to a server that hangs must end.
std::unique_ptr<grpc::ClientContext> ContextWithDeadline(absl::Duration timeout);

}  // namespace lf
