// How `lightfarm` and `lightfarm-worker` reach the server: the address, TLS (the CA that signs
// the server's certificate, and a client certificate for mutual TLS) and the bearer token that
// every call carries in its `authorization` metadata.
#pragma once

#include <grpcpp/channel.h>
#include <grpcpp/support/channel_arguments.h>

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "absl/time/time.h"

namespace lf {

// How often OpenChannel's channels ping an idle connection; servers must accept pings this often
// (GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS at most this).
inline constexpr absl::Duration kKeepaliveInterval = absl::Seconds(10);

struct ChannelOptions {
    std::string address;   // HOST:PORT
    std::string tls_ca;    // PEM file: TLS on, trusting this CA; "" for plain TCP
    std::string tls_cert;  // PEM client certificate (mutual TLS); needs tls_ca and tls_key
    std::string tls_key;
    std::string token_file;  // a file holding the token; "" for LIGHTFARM_TOKEN or none
};

// The content of a PEM file: NotFound naming the flag and the file when it cannot be read,
// InvalidArgument when it holds no PEM block. The server's TLS files are read by it too.
absl::StatusOr<std::string> ReadPemFile(const std::string& flag, const std::string& path);

// The token: token_file's first line when given (NotFound or InvalidArgument naming the file
// when it cannot be read or is empty), else the LIGHTFARM_TOKEN environment variable, else "".
absl::StatusOr<std::string> LoadToken(const ChannelOptions& options);

// A channel to options.address with the options' TLS, whose calls carry the token (when one is
// given). InvalidArgument naming the flag and the file for unreadable or inconsistent files.
absl::StatusOr<std::shared_ptr<grpc::Channel>> OpenChannel(const ChannelOptions& options,
                                                           const grpc::ChannelArguments& args = {});

}  // namespace lf
