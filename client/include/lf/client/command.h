// A subcommand of `lightfarm`: its CLI11 parser and what runs when the user picks it.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <string>

#include "absl/status/status.h"

namespace lf {

struct Command {
    CLI::App* parser;
    std::function<int()> run;  // the process exit status
};

// Prints "lightfarm: error: <message>" and returns 1.
int ReportError(const absl::Status& status);

Command AddRenderCommand(CLI::App& app);
Command AddBenchCommand(CLI::App& app);
Command AddConvergeCommand(CLI::App& app);
Command AddPlanCommand(CLI::App& app);

// The farm (submit_command.cc, farm_commands.cc): jobs on a lightfarm-server.
Command AddSubmitCommand(CLI::App& app);
Command AddListCommand(CLI::App& app);
Command AddStatusCommand(CLI::App& app);
Command AddWatchCommand(CLI::App& app);
Command AddFetchCommand(CLI::App& app);
Command AddCancelCommand(CLI::App& app);
Command AddPriorityCommand(CLI::App& app);
Command AddDeleteCommand(CLI::App& app);
Command AddWorkersCommand(CLI::App& app);
Command AddTasksCommand(CLI::App& app);
Command AddLogsCommand(CLI::App& app);
// Job management (issue 30; job_management_commands.cc).
Command AddRequeueCommand(CLI::App& app);
Command AddPauseCommand(CLI::App& app);
Command AddResumeCommand(CLI::App& app);
// History (issue 30; farm_commands.cc).
Command AddStatsCommand(CLI::App& app);
// Dependencies (issue 30; job_management_commands.cc).
Command AddDependCommand(CLI::App& app);

}  // namespace lf
