#include "lf/client/farm_flags.h"

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "lf/proto/channel_flags.h"

namespace lf {

void AddServerOption(CLI::App* cmd, FarmFlags& flags) {
    cmd->add_option("--server", flags.channel.address, "HOST:PORT of lightfarm-server")
        ->envname("LIGHTFARM_SERVER")
        ->capture_default_str();
    AddChannelFlags(cmd, &flags.channel);
    cmd->parse_complete_callback([&flags] {
        if (absl::StatusOr<std::shared_ptr<grpc::Channel>> channel = OpenChannel(flags.channel);
            !channel.ok()) {
            throw CLI::ValidationError(std::string(channel.status().message()));
        }
    });
}

void AddRetryOption(CLI::App* cmd, FarmFlags& flags) {
    cmd->add_option("--retry-seconds", flags.retry_seconds,
                    "while the server is unreachable (restarting, say), retry for this long "
                    "before giving up; 0: do not retry")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 86400.0));
}

}  // namespace lf
