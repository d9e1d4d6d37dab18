#include "lf/proto/channel.h"

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>
#include <grpcpp/support/client_interceptor.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"

namespace lf {

namespace {

absl::StatusOr<std::string> ReadFile(const std::string& flag, const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return absl::NotFoundError(absl::StrCat(flag, " ", path, ": cannot be read"));
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

// Adds the bearer token to every call's metadata. An interceptor rather than call credentials:
// gRPC sends call credentials over TLS only, and a token also guards a loopback server.
class TokenInterceptor final : public grpc::experimental::Interceptor {
  public:
    explicit TokenInterceptor(const std::string* header) : header_(header) {}
    void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
        if (methods->QueryInterceptionHookPoint(
                grpc::experimental::InterceptionHookPoints::PRE_SEND_INITIAL_METADATA)) {
            methods->GetSendInitialMetadata()->insert({"authorization", *header_});
        }
        methods->Proceed();
    }

  private:
    const std::string* header_;
};

class TokenInterceptorFactory final : public grpc::experimental::ClientInterceptorFactoryInterface {
  public:
    explicit TokenInterceptorFactory(const std::string& token) : header_("Bearer " + token) {}
    grpc::experimental::Interceptor* CreateClientInterceptor(
        grpc::experimental::ClientRpcInfo*) override {
        return new TokenInterceptor(&header_);
    }

  private:
    const std::string header_;  // lives as long as the channel, which owns the factory
};

}  // namespace

absl::StatusOr<std::string> ReadPemFile(const std::string& flag, const std::string& path) {
    absl::StatusOr<std::string> pem = ReadFile(flag, path);
    if (pem.ok() && !absl::StrContains(*pem, "-----BEGIN ")) {
        return absl::InvalidArgumentError(
            absl::StrCat(flag, " ", path, ": not a PEM file (no -----BEGIN line)"));
    }
    return pem;
}

absl::StatusOr<std::string> LoadToken(const ChannelOptions& options) {
    std::string token;
    if (!options.token_file.empty()) {
        absl::StatusOr<std::string> text = ReadFile("--token-file", options.token_file);
        if (!text.ok()) return text.status();
        token = text->substr(0, text->find('\n'));
        if (absl::StripAsciiWhitespace(token).empty()) {
            return absl::InvalidArgumentError(
                absl::StrCat("--token-file ", options.token_file, ": empty"));
        }
    } else if (const char* env = std::getenv("LIGHTFARM_TOKEN")) {
        token = env;
    }
    return std::string(absl::StripAsciiWhitespace(token));
}

absl::StatusOr<std::shared_ptr<grpc::Channel>> OpenChannel(const ChannelOptions& options,
                                                           const grpc::ChannelArguments& args) {
    std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
    if (options.tls_ca.empty()) {
        if (!options.tls_cert.empty() || !options.tls_key.empty()) {
            return absl::InvalidArgumentError(
                "--tls-cert and --tls-key need --tls-ca: TLS is on with the server's CA");
        }
    } else {
        grpc::SslCredentialsOptions ssl;
        absl::StatusOr<std::string> ca = ReadPemFile("--tls-ca", options.tls_ca);
        if (!ca.ok()) return ca.status();
        ssl.pem_root_certs = *ca;
        if (options.tls_cert.empty() != options.tls_key.empty()) {
            return absl::InvalidArgumentError("--tls-cert and --tls-key go together");
        }
        if (!options.tls_cert.empty()) {
            absl::StatusOr<std::string> cert = ReadPemFile("--tls-cert", options.tls_cert);
            if (!cert.ok()) return cert.status();
            absl::StatusOr<std::string> key = ReadPemFile("--tls-key", options.tls_key);
            if (!key.ok()) return key.status();
            ssl.pem_cert_chain = *cert;
            ssl.pem_private_key = *key;
        }
        credentials = grpc::SslCredentials(ssl);
    }
    absl::StatusOr<std::string> token = LoadToken(options);
    if (!token.ok()) return token.status();
    // Keepalive pings find a connection whose link went down (a cable, a host gone, a
    // partition) within 15 s: without them a call waits on TCP's retransmissions, which back off
    // to minutes, long after the link is back. lightfarm-server accepts pings this often.
    grpc::ChannelArguments channel_args = args;
    channel_args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS,
                        int(kKeepaliveInterval / absl::Milliseconds(1)));
    channel_args.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 5000);
    channel_args.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
    channel_args.SetInt(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);
    std::vector<std::unique_ptr<grpc::experimental::ClientInterceptorFactoryInterface>> factories;
    if (!token->empty()) factories.push_back(std::make_unique<TokenInterceptorFactory>(*token));
    return grpc::experimental::CreateCustomChannelWithInterceptors(
        options.address, credentials, channel_args, std::move(factories));
}

}  // namespace lf
