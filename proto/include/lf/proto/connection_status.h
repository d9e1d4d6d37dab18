// A failed call's status as the user of `lightfarm` or `lightfarm-worker` should read it. gRPC
// reports TLS on one side only as "Socket closed" or an SSL error, both UNAVAILABLE like a server
// that is down; this says which side speaks TLS and which flag to change.
#pragma once

#include <grpcpp/support/status.h>

#include "absl/status/status.h"
#include "lf/proto/channel.h"

namespace lf {

// FailedPrecondition for a TLS failure that retrying cannot mend (a plain-text server, a
// certificate refused); Unavailable, naming the server, when it cannot be reached (with a word
// on --tls-ca when a plain-text connection was closed before any answer, as TLS servers do);
// otherwise the server's own status.
absl::Status ConnectionStatus(const grpc::Status& status, const ChannelOptions& options);

}  // namespace lf
