// lightfarm: the command-line client. Each subcommand lives in its own *_command.cc.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <vector>

#include "lf/client/command.h"
#include "lf/version.h"

int main(int argc, char** argv) {
    CLI::App app{
        "lightfarm: physically based rendering of the rendering equation, on one machine or a "
        "farm.\nSee docs/scene-format.md for the scene format."};
    app.set_version_flag("--version", std::string(lf::kVersion));
    app.require_subcommand(1);
    std::string log_level = "info";
    app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
        ->capture_default_str();

    const std::vector<lf::Command> commands = {
        lf::AddRenderCommand(app),  lf::AddBenchCommand(app),    lf::AddConvergeCommand(app),
        lf::AddPlanCommand(app),    lf::AddSubmitCommand(app),   lf::AddListCommand(app),
        lf::AddStatusCommand(app),  lf::AddWatchCommand(app),    lf::AddFetchCommand(app),
        lf::AddCancelCommand(app),  lf::AddPriorityCommand(app), lf::AddDeleteCommand(app),
        lf::AddWorkersCommand(app), lf::AddTasksCommand(app),    lf::AddLogsCommand(app),
        lf::AddRequeueCommand(app), lf::AddPauseCommand(app),    lf::AddResumeCommand(app),
        lf::AddStatsCommand(app),
        lf::AddDependCommand(app),
    };
    CLI11_PARSE(app, argc, argv);
    spdlog::set_level(spdlog::level::from_str(log_level));
    for (const lf::Command& command : commands) {
        if (*command.parser) return command.run();
    }
    return 0;
}
