// Job management (issue 30): `lightfarm requeue`, `pause`, `resume` and `depend`. See docs/farm.md,
// Managing jobs.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "lf/client/command.h"
#include "lf/client/farm_client.h"
#include "lf/client/farm_flags.h"
#include "lf/job/job_record.h"
#include "lf/job/shot.h"
#include "lf/wire/conversions.h"
#include "lightfarm/v1/job_service.grpc.pb.h"

namespace lf {

namespace pb = lightfarm::v1;

namespace {

// A subcommand acting on one job: its `job` argument and --server.
struct JobSubcommand {
    CLI::App* cmd;
    std::shared_ptr<FarmFlags> flags = std::make_shared<FarmFlags>();
    std::shared_ptr<std::string> id = std::make_shared<std::string>();
};

JobSubcommand AddJobSubcommand(CLI::App& app, const char* name, const char* help) {
    JobSubcommand sub{app.add_subcommand(name, help)};
    sub.cmd->add_option("job", *sub.id, "job id")->required();
    AddServerOption(sub.cmd, *sub.flags);
    return sub;
}

}  // namespace

Command AddRequeueCommand(CLI::App& app) {
    auto [cmd, flags, id] = AddJobSubcommand(
        app, "requeue",
        "Put a job's tasks back in the queue (the job's owner or an admin).\n"
        "--failed (the default): its failed tasks, their failures reset, and its blocklist\n"
        "cleared; a failed or cancelled job is queued again and renders on from the tasks it had\n"
        "done. --frames A-B[:STEP]: those frames of an ended shot, a succeeded one too, are\n"
        "rendered again from scratch (their EXRs dropped and written again), the job queued\n"
        "until they are done. Refused while a job it runs after is failed or cancelled\n"
        "(requeue that one first), and --frames while jobs that run after it are active.");
    auto frames = std::make_shared<std::string>();
    auto failed = std::make_shared<bool>(true);
    // Names the default, and is captured below only to outlive the parse: the failed tasks are
    // requeued whenever --frames is not given, and a job --frames takes up again has every
    // task's failures reset too.
    cmd->add_flag("--failed", *failed, "requeue the failed tasks (the default)");
    cmd->add_option("--frames", *frames,
                    "render these frames of an ended shot again (submit's --frames syntax; a "
                    "chunk's other frames with them)")
        ->type_name("A-B[:STEP]");
    return {
        cmd, [flags, id, frames, failed] {
            pb::RequeueJobRequest req;
            req.set_job_id(*id);
            if (!frames->empty()) {
                absl::StatusOr<FrameRange> range = ParseFrameRange(*frames);
                if (!range.ok()) {
                    return ReportError(absl::InvalidArgumentError(
                        absl::StrCat("--frames: ", range.status().message())));
                }
                req.set_frames(FrameRangeText(*range));
            }
            pb::Job job;
            absl::Status s = FarmClient(*flags).Call(&pb::JobService::Stub::RequeueJob, req, &job);
            if (!s.ok()) return ReportError(s);
            std::printf("job %s %s (%d/%d tasks done)\n", job.id().c_str(),
                        JobStateName(FromProto(job.state())), job.tasks_done(), job.tasks_total());
            return 0;
        }};
}

namespace {

// `pause` or `resume`.
template <typename Request>
Command AddPausingCommand(CLI::App& app, const char* name, const char* help,
                          FarmClient::Rpc<Request, pb::Job> rpc) {
    auto [cmd, flags, id] = AddJobSubcommand(app, name, help);
    return {cmd, [flags, id, rpc] {
                Request req;
                req.set_job_id(*id);
                pb::Job job;
                if (absl::Status s = FarmClient(*flags).Call(rpc, req, &job); !s.ok()) {
                    return ReportError(s);
                }
                std::printf("job %s %s\n", job.id().c_str(), job.paused() ? "paused" : "resumed");
                return 0;
            }};
}

}  // namespace

Command AddPauseCommand(CLI::App& app) {
    return AddPausingCommand<pb::PauseJobRequest>(
        app, "pause",
        "Pause a queued or running job: it leases nothing new, its running tasks finish and\n"
        "merge; it stays paused across a server restart until `resume` (owner or admin).",
        &pb::JobService::Stub::PauseJob);
}

Command AddResumeCommand(CLI::App& app) {
    return AddPausingCommand<pb::ResumeJobRequest>(
        app, "resume", "Resume a paused job: its tasks are leased again.",
        &pb::JobService::Stub::ResumeJob);
}

Command AddDependCommand(CLI::App& app) {
    auto [cmd, flags, id] = AddJobSubcommand(
        app, "depend",
        "Make a queued job also wait for other jobs: it leases nothing until each has\n"
        "succeeded, and fails when one fails or is cancelled (the job's owner or an admin). A\n"
        "cycle is refused.");
    auto after = std::make_shared<std::vector<std::string>>();
    cmd->add_option("--after", *after, "job ids, comma-separated or repeated")
        ->required()
        ->delimiter(',');
    return {cmd, [flags, id, after] {
                pb::AddJobDependenciesRequest req;
                req.set_job_id(*id);
                for (const std::string& dep : *after) req.add_after(dep);
                pb::Job job;
                if (absl::Status s = FarmClient(*flags).Call(
                        &pb::JobService::Stub::AddJobDependencies, req, &job);
                    !s.ok()) {
                    return ReportError(s);
                }
                std::printf("job %s runs after %s%s\n", job.id().c_str(),
                            absl::StrJoin(job.after(), ", ").c_str(),
                            job.waiting_reason().empty()
                                ? ""
                                : absl::StrCat("; ", job.waiting_reason()).c_str());
                return 0;
            }};
}

}  // namespace lf
