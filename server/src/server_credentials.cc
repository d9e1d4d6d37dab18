#include "lf/server/server_credentials.h"

#include <grpcpp/security/server_credentials.h>

#include "lf/proto/channel.h"

namespace lf {

absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> MakeServerCredentials(
    const ServerTlsFiles& files) {
    if (!files.enabled()) {
        if (!files.key.empty() || !files.client_ca.empty()) {
            return absl::InvalidArgumentError(
                "--tls-key and --tls-client-ca need --tls-cert: TLS is on with a certificate");
        }
        return grpc::InsecureServerCredentials();
    }
    if (files.key.empty()) return absl::InvalidArgumentError("--tls-cert needs --tls-key");
    absl::StatusOr<std::string> cert = ReadPemFile("--tls-cert", files.cert);
    if (!cert.ok()) return cert.status();
    absl::StatusOr<std::string> key = ReadPemFile("--tls-key", files.key);
    if (!key.ok()) return key.status();
    grpc::SslServerCredentialsOptions options;
    options.pem_key_cert_pairs.push_back({*key, *cert});
    if (!files.client_ca.empty()) {
        absl::StatusOr<std::string> ca = ReadPemFile("--tls-client-ca", files.client_ca);
        if (!ca.ok()) return ca.status();
        options.pem_root_certs = *ca;
        // Clients (`lightfarm`) may come without a certificate; workers must bring one, which
        // the services check. A certificate another CA signed fails the handshake.
        options.client_certificate_request = GRPC_SSL_REQUEST_CLIENT_CERTIFICATE_AND_VERIFY;
    }
    return grpc::SslServerCredentials(options);
}

}  // namespace lf
