// --server, the TLS and token flags, and --retry-seconds: how the farm commands reach a
// lightfarm-server.
#pragma once

#include <CLI/CLI.hpp>

#include "lf/proto/channel.h"

namespace lf {

struct FarmFlags {
    ChannelOptions channel{.address = "127.0.0.1:7070"};
    double retry_seconds = 60;  // how long submit and watch ride out an unreachable server
};

// --server and the TLS and token flags; files they name are checked once the command line is
// parsed, so that a wrong path is said before any work.
void AddServerOption(CLI::App* cmd, FarmFlags& flags);

// --retry-seconds.
void AddRetryOption(CLI::App* cmd, FarmFlags& flags);

}  // namespace lf
