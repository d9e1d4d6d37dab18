// The TLS settings of lightfarm-server's gRPC port, made from PEM files.
#pragma once

#include <grpcpp/security/server_credentials.h>

#include <memory>
#include <string>

#include "absl/status/statusor.h"

namespace lf {

struct ServerTlsFiles {
    std::string cert;       // PEM certificate chain; "" for no TLS
    std::string key;        // its PEM private key
    std::string client_ca;  // PEM CA that signs client certificates; "" for none
    bool enabled() const { return !cert.empty(); }
};

// Insecure credentials without a certificate; TLS with one. With a client CA, clients that
// present a certificate must present one it signed (the handshake fails otherwise); whether a
// caller must present one at all is the services' to say (CallGuard::worker_certificates).
// NotFound or InvalidArgument naming the file that is missing or not PEM, or a key without
// its certificate.
absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> MakeServerCredentials(
    const ServerTlsFiles& files);

}  // namespace lf
