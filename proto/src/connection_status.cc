#include "lf/proto/connection_status.h"

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "lf/proto/grpc_status.h"

namespace lf {

absl::Status ConnectionStatus(const grpc::Status& s, const ChannelOptions& options) {
    if (s.error_code() != grpc::StatusCode::UNAVAILABLE) return FromGrpcStatus(s);
    const std::string& why = s.error_message();
    const std::string& server = options.address;
    if (!options.tls_ca.empty() && (absl::StrContains(why, "wrong version number") ||
                                    absl::StrContains(why, "WRONG_VERSION_NUMBER"))) {
        return absl::FailedPreconditionError(absl::StrCat(
            "server ", server,
            " does not speak TLS (it answered the TLS handshake in plain "
            "text): leave out --tls-ca, or start the server with --tls-cert and --tls-key (",
            why, ")"));
    }
    if (!options.tls_ca.empty() && absl::StrContains(why, "ALPN")) {
        return absl::FailedPreconditionError(
            absl::StrCat("server ", server,
                         " speaks TLS but not gRPC (is it the server's --http port?) (", why, ")"));
    }
    if (absl::StrContains(why, "SSL_ERROR_SSL")) {
        return absl::FailedPreconditionError(absl::StrCat(
            "TLS handshake with server ", server, " failed (", why,
            "): check --tls-ca, the server's certificate names, and --tls-cert/--tls-key if the "
            "server asks for client certificates"));
    }
    if (options.tls_ca.empty() && absl::StrContains(why, "Socket closed")) {
        // Unavailable still: a server going down closes connections too, and that is retried.
        return absl::UnavailableError(absl::StrCat(
            "server ", server,
            " closed the connection before answering: it speaks TLS, most "
            "likely (a TLS server closes plain-text connections so); give the CA of its "
            "certificate with --tls-ca (",
            why, ")"));
    }
    return absl::UnavailableError(absl::StrCat("server ", server, " not reachable: ", why));
}

}  // namespace lf
