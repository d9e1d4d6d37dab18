// The flags of lf::ChannelOptions, one list for `lightfarm` and `lightfarm-worker`. Header-only:
// CLI11 is the binaries' dependency, not lf_proto's.
#pragma once

#include <CLI/CLI.hpp>

#include "lf/proto/channel.h"

namespace lf {

// --tls-ca, --tls-cert, --tls-key and --token-file (the server address is each binary's own).
inline void AddChannelFlags(CLI::App* cmd, ChannelOptions* options) {
    cmd->add_option("--tls-ca", options->tls_ca,
                    "PEM CA that signed the server's certificate: TLS on (the server's name or "
                    "address must be in its certificate)")
        ->envname("LIGHTFARM_TLS_CA");
    cmd->add_option("--tls-cert", options->tls_cert,
                    "PEM client certificate, for a server with --tls-client-ca");
    cmd->add_option("--tls-key", options->tls_key, "PEM private key of --tls-cert");
    cmd->add_option("--token-file", options->token_file,
                    "file whose first line is the bearer token (else LIGHTFARM_TOKEN is used)");
}

}  // namespace lf
