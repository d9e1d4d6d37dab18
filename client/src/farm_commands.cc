// The farm subcommands of `lightfarm` that ask lightfarm-server's JobService about jobs and act
// on them: list, status, watch, fetch, cancel, priority, delete, workers, tasks, logs and stats,
// each through a FarmClient (`submit` is submit_command.cc).
#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "lf/client/command.h"
#include "lf/client/farm_client.h"
#include "lf/client/farm_flags.h"
#include "lf/client/method_flags.h"
#include "lf/client/output_flags.h"
#include "lf/client/progress_bar.h"
#include "lf/core/image_io.h"
#include "lf/core/log.h"
#include "lf/core/plural.h"
#include "lf/job/farm_stats.h"
#include "lf/job/job_record.h"
#include "lf/job/job_spec.h"
#include "lf/wire/conversions.h"
#include "lightfarm/v1/job_service.grpc.pb.h"

namespace lf {

namespace fs = std::filesystem;
namespace pb = lightfarm::v1;

namespace {

// How much of a worker's identity `workers`, `tasks` and `logs` show: the same in each, so that
// one table's worker is found in the other.
constexpr size_t kWorkerIdShown = 64;

void AddJsonFlag(CLI::App* cmd, bool& json) {
    cmd->add_flag("--json", json,
                  "one JSON object a line instead of the table: the wire message's fields "
                  "(lightfarm.v1, proto field names, every field present)");
}

// The message as one line of JSON, as protobuf's own mapping writes it (strings escaped, so no
// name a worker or submitter chose can move the terminal).
std::string JsonLine(const google::protobuf::Message& message) {
    google::protobuf::util::JsonPrintOptions options;
    options.always_print_primitive_fields = true;
    options.preserve_proto_field_names = true;
    std::string line;
    if (!google::protobuf::util::MessageToJsonString(message, &line, options).ok()) return "";
    return line + "\n";
}

void PrintJson(const google::protobuf::Message& message) {
    std::fputs(JsonLine(message).c_str(), stdout);
}

std::string StateName(pb::Job::State s) { return absl::AsciiStrToLower(pb::Job::State_Name(s)); }
// What list and status show: a paused job (issue 30) as "paused", a queued one waiting for its
// dependencies as "waiting", else its state.
std::string ShownState(const pb::Job& job) {
    if (IsFinal(FromProto(job.state()))) return StateName(job.state());
    if (job.paused()) return "paused";
    return job.waiting_for_size() > 0 ? "waiting" : StateName(job.state());
}

// "2026-11-26 23:41:07" in the machine's time zone, as a user reads a clock.
std::string LocalTime(int64_t unix_ms) {
    return absl::FormatTime("%Y-%m-%d %H:%M:%S", absl::FromUnixMillis(unix_ms),
                            absl::LocalTimeZone());
}

// How long the job has rendered (from its first lease to its end, or to now), or "-" before
// its first lease: "42s", "3m07s", "2h05m".
std::string ElapsedText(const pb::Job& job) {
    if (job.started_unix_ms() <= 0) return "-";
    const int64_t end =
        job.finished_unix_ms() > 0 ? job.finished_unix_ms() : absl::ToUnixMillis(absl::Now());
    const int64_t s = std::max<int64_t>(0, (end - job.started_unix_ms()) / 1000);
    if (s < 60) return absl::StrCat(s, "s");
    if (s < 3600) return absl::StrFormat("%dm%02ds", s / 60, s % 60);
    return absl::StrFormat("%dh%02dm", s / 3600, s / 60 % 60);
}

// A shot's ", 1/3 frames" done; "" for a still.
std::string FramesDone(const pb::Job& job) {
    if (job.frames_total() == 0) return "";
    return absl::StrCat(", ", job.frames_done(), "/", job.frames_total(), " frames");
}

// "5/12" tasks; a shot's "5/12, 1/3 frames".
std::string Progress(const pb::Job& job) {
    return absl::StrCat(job.tasks_done(), "/", job.tasks_total(), FramesDone(job));
}

// A shot's frames and each one's progress: "1 done, 2 3/4, 3 0/4".
std::string FramesText(const pb::Job& job) {
    std::string text;
    for (const pb::FrameProgress& f : job.frames()) {
        absl::StrAppend(&text, text.empty() ? "" : ", ", f.frame(), " ",
                        f.done() ? "done" : absl::StrCat(f.tasks_done(), "/", f.tasks_total()));
        // What its merged tasks took on their workers (issue 30's per-frame times).
        if (f.render_seconds() > 0) {
            absl::StrAppend(&text, absl::StrFormat(" (%.1f s, %.1f s CPU)", f.render_seconds(),
                                                   f.cpu_seconds()));
        }
    }
    return text;
}

void PrintJob(const pb::Job& job) {
    const int64_t now = absl::ToUnixMillis(absl::Now());
    auto seconds = [](int64_t from, int64_t to) { return double(to - from) / 1000.0; };
    std::printf("job %s: %s\n", job.id().c_str(), ShownState(job).c_str());
    std::printf("  name      %s\n", job.name().c_str());
    if (!job.owner().empty()) std::printf("  owner     %s\n", job.owner().c_str());
    std::printf("  method    %s\n",
                job.params().method().empty() ? "path" : job.params().method().c_str());
    std::printf("  image     %dx%d, %llu spp, seed %llu, max depth %d, tile %d, %s\n", job.width(),
                job.height(), (unsigned long long)job.params().spp(),
                (unsigned long long)job.params().seed(), job.params().max_depth(),
                job.params().tile(), Plural(job.params().passes(), "pass").c_str());
    JobSpec spec;
    FromProto(job.params(), &spec);
    // Radiosity samples no lights: its light strategy would say nothing.
    std::printf("  sampling  %s sampler%s\n", SamplerTypeName(spec.sampler),
                FindMethod(spec.method) == Method::kRadiosity
                    ? ""
                    : absl::StrCat(", ", LightStrategyName(spec.light_strategy), " light sampling")
                          .c_str());
    if (IsAdaptive(spec.adaptive)) {
        std::printf(
            "  adaptive  %s %g, time limit %g s, at most %llu spp\n",
            spec.adaptive.noise_threshold > 0 ? "noise threshold (per pixel)" : "target error",
            spec.adaptive.noise_threshold > 0 ? spec.adaptive.noise_threshold
                                              : spec.adaptive.target_error,
            spec.adaptive.time_limit, (unsigned long long)spec.adaptive.max_spp);
    }
    if (spec.shot.frames) {
        std::printf(
            "  frames    %s at %g fps, %d done of %d%s\n",
            FrameRangeText(*spec.shot.frames).c_str(), spec.shot.fps, job.frames_done(),
            job.frames_total(),
            spec.shot.chunk > 1 ? absl::StrCat(", ", spec.shot.chunk, " a task").c_str() : "");
        std::printf("            %s\n", FramesText(job).c_str());
    }
    std::printf("  priority  %d\n", job.priority());
    if (job.tags_size() > 0 || job.max_workers() > 0) {
        std::printf(
            "  workers   %s%s\n",
            job.tags_size() > 0 ? absl::StrCat("tags ", absl::StrJoin(job.tags(), ",")).c_str()
                                : "any",
            job.max_workers() > 0 ? absl::StrCat(", at most ", job.max_workers()).c_str() : "");
    }
    if (job.after_size() > 0) {
        std::printf("  after     %s\n", LogSafe(absl::StrJoin(job.after(), ", ")).c_str());
    }
    if (!job.waiting_reason().empty()) {
        std::printf("  waiting   %s\n", LogSafe(job.waiting_reason()).c_str());
    }
    std::printf("  tasks     %d/%d done, %d running, %d retried, %d leased\n", job.tasks_done(),
                job.tasks_total(), job.tasks_running(), job.retries(), job.tasks_leased());
    std::printf("  samples   %llu (%llu rays, %llu NaN/Inf)\n", (unsigned long long)job.samples(),
                (unsigned long long)job.rays(), (unsigned long long)job.invalid_samples());
    if (job.started_unix_ms() > 0) {
        const int64_t end = job.finished_unix_ms() > 0 ? job.finished_unix_ms() : now;
        std::printf("  time      %.1f s queued, %.1f s rendering\n",
                    seconds(job.submitted_unix_ms(), job.started_unix_ms()),
                    seconds(job.started_unix_ms(), end));
    } else {
        std::printf("  time      %.1f s queued\n", seconds(job.submitted_unix_ms(), now));
    }
    if (job.render_seconds() > 0) {
        std::printf("  worked    %.2f s rendering, %.2f s CPU, on workers (merged tasks)\n",
                    job.render_seconds(), job.cpu_seconds());
    }
    std::string when = absl::StrCat("  submitted ", LocalTime(job.submitted_unix_ms()));
    if (job.started_unix_ms() > 0)
        absl::StrAppend(&when, ", started ", LocalTime(job.started_unix_ms()));
    if (job.finished_unix_ms() > 0) {
        absl::StrAppend(&when, ", ended ", LocalTime(job.finished_unix_ms()));
    }
    std::printf("%s\n", when.c_str());
    // A failed job's error names the failing task; its last error says what that one did.
    if ((!IsFinal(FromProto(job.state())) || job.state() == pb::Job::FAILED) &&
        !job.last_error().empty()) {
        std::printf("  last error  %s\n", job.last_error().c_str());
    }
    if (!job.error().empty()) std::printf("  error     %s\n", job.error().c_str());
    // Job management (issue 30).
    std::printf("  attempts  %d a task; blocklist after %d failures\n", job.max_attempts(),
                job.blocklist_after());
    for (const pb::BlockedWorker& w : job.blocklist()) {
        std::printf("  blocklisted: %s (%s, last: %s)\n", w.worker().c_str(),
                    Plural(w.failures(), "failure").c_str(), w.last_error().c_str());
    }
}

// The job's EXR at paths.exr, and its preview at paths.png and false-colour PNG at
// paths.false_color, made here from the EXR (fetched into a temporary file when -o names only
// the PNG). A shot's `frame` is that frame's.
absl::Status FetchOutputs(const FarmFlags& flags, const std::string& id, const OutputPaths& paths,
                          const OutputFlags& output, bool preview,
                          std::optional<int> frame = std::nullopt) {
    if (absl::Status s = CheckWritable(paths.png); !s.ok()) return s;
    if (absl::Status s = CheckWritable(paths.false_color); !s.ok()) return s;
    const std::string exr = paths.exr.empty() ? paths.png + ".exr.part" : paths.exr;
    if (absl::Status s = FarmClient(flags).FetchResult(id, exr, preview, frame); !s.ok()) return s;
    if (paths.png.empty() && !output.false_color) return absl::OkStatus();
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    absl::Status written = file.status();
    if (written.ok() && !paths.png.empty()) {
        written = WritePng(paths.png, file->image, output.preview);
    }
    if (written.ok() && output.false_color) {
        written = WriteFalseColorPng(paths.false_color, file->image, *output.false_color);
    }
    std::error_code ignored;  // a temporary file left behind is harmless
    if (paths.exr.empty()) fs::remove(exr, ignored);
    return written;
}

absl::StatusOr<pb::Job> GetJob(const FarmFlags& flags, const std::string& id) {
    pb::GetJobRequest req;
    req.set_job_id(id);
    pb::Job job;
    if (absl::Status s = FarmClient(flags).Call(&pb::JobService::Stub::GetJob, req, &job);
        !s.ok()) {
        return s;
    }
    return job;
}

// The frames `fetch` writes: those --frames names (each must be the shot's), or every finished
// one (every one with --preview); -o and --png must number them (lf::CheckFramePattern).
absl::StatusOr<std::vector<int>> FramesToFetch(const pb::Job& job, const std::string& flag,
                                               const OutputPaths& paths, bool preview) {
    JobSpec spec;
    FromProto(job.params(), &spec);
    const FrameRange& shot = *spec.shot.frames;
    std::vector<int> frames;
    FrameRange named = shot;
    if (!flag.empty()) {
        absl::StatusOr<FrameRange> range = ParseFrameRange(flag);
        if (!range.ok()) return range.status();
        named = *range;
        for (int i = 0; i < named.count(); ++i) {
            if (!shot.Contains(named.at(i))) {
                return absl::InvalidArgumentError(
                    absl::StrCat("--frames ", flag, ": frame ", named.at(i), " is not one of job ",
                                 job.id(), "'s (", FrameRangeText(shot), ")"));
            }
            frames.push_back(named.at(i));
        }
    } else {
        for (const pb::FrameProgress& f : job.frames()) {
            if (f.done() || preview) frames.push_back(f.frame());
        }
        if (frames.empty()) {
            return absl::FailedPreconditionError(
                absl::StrCat("job ", job.id(), " has no finished frame yet (0/", job.frames_total(),
                             "); --preview fetches what is merged so far"));
        }
        if (frames.size() == 1) named = {frames[0], frames[0], 1};
    }
    for (const auto& [name, pattern] : {std::pair{"-o", paths.exr}, {"--png", paths.png}}) {
        if (pattern.empty()) continue;
        if (absl::Status s = CheckFramePattern(name, pattern, named); !s.ok()) return s;
    }
    return frames;
}

}  // namespace

Command AddListCommand(CLI::App& app) {
    auto flags = std::make_shared<FarmFlags>();
    auto limit = std::make_shared<int>(0);
    auto json = std::make_shared<bool>(false);
    CLI::App* cmd = app.add_subcommand("list", "List the server's jobs, newest first.");
    cmd->add_option("--limit", *limit, "at most this many jobs; 0 lists them all")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber);
    AddJsonFlag(cmd, *json);
    AddServerOption(cmd, *flags);
    return {cmd, [flags, limit, json] {
                // A page per call, so that no answer grows with the number of jobs.
                constexpr int kPage = 500;
                FarmClient client(*flags);
                pb::ListJobsRequest req;
                int listed = 0;
                // Printed only once every page has come: a failed call prints nothing to stdout.
                std::string out =
                    *json ? ""
                          : absl::StrFormat("%-16s %-10s %-12s %-9s %8s %11s %9s %-19s %8s  %s\n",
                                            "JOB", "STATE", "OWNER", "METHOD", "PRIORITY", "TASKS",
                                            "SPP", "SUBMITTED", "TIME", "NAME");
                do {
                    req.set_page_size(*limit > 0 ? std::min(kPage, *limit - listed) : kPage);
                    pb::ListJobsResponse resp;
                    absl::Status s = client.Call(&pb::JobService::Stub::ListJobs, req, &resp);
                    if (!s.ok()) return ReportError(s);
                    for (const pb::Job& job : resp.jobs()) {
                        if (*json) {
                            absl::StrAppend(&out, JsonLine(job));
                            continue;
                        }
                        absl::StrAppendFormat(
                            &out, "%-16s %-10s %-12s %-9s %8d %11s %9llu %-19s %8s  %s\n",
                            job.id().c_str(), ShownState(job).c_str(),
                            job.owner().empty() ? "-" : job.owner().c_str(),
                            job.params().method().empty() ? "path" : job.params().method().c_str(),
                            job.priority(), Progress(job).c_str(),
                            (unsigned long long)job.params().spp(),
                            LocalTime(job.submitted_unix_ms()).c_str(), ElapsedText(job).c_str(),
                            job.name().c_str());
                    }
                    listed += resp.jobs_size();
                    req.set_page_token(resp.next_page_token());
                } while (!req.page_token().empty() && (*limit == 0 || listed < *limit));
                std::fputs(out.c_str(), stdout);
                return 0;
            }};
}

Command AddStatusCommand(CLI::App& app) {
    auto flags = std::make_shared<FarmFlags>();
    auto id = std::make_shared<std::string>();
    auto json = std::make_shared<bool>(false);
    CLI::App* cmd = app.add_subcommand("status", "Show one job: state, progress, error.");
    cmd->add_option("job", *id, "job id")->required();
    AddJsonFlag(cmd, *json);
    AddServerOption(cmd, *flags);
    return {cmd, [flags, id, json] {
                pb::GetJobRequest req;
                req.set_job_id(*id);
                pb::Job job;
                const absl::Status s =
                    FarmClient(*flags).Call(&pb::JobService::Stub::GetJob, req, &job);
                if (!s.ok()) return ReportError(s);
                if (*json) {
                    PrintJson(job);
                } else {
                    PrintJob(job);
                }
                return 0;
            }};
}

Command AddWatchCommand(CLI::App& app) {
    auto flags = std::make_shared<FarmFlags>();
    auto id = std::make_shared<std::string>();
    CLI::App* cmd = app.add_subcommand(
        "watch",
        "Follow a job until it ends (progress bar on a terminal). Exit status 0 only when it\n"
        "succeeded.");
    cmd->add_option("job", *id, "job id")->required();
    AddServerOption(cmd, *flags);
    AddRetryOption(cmd, *flags);
    return {cmd, [flags, id] {
                FarmClient client(*flags);
                return WatchJob(client, *id);
            }};
}

int WatchJob(FarmClient& client, const std::string& job_id) {
    ProgressBar bar(job_id);
    absl::StatusOr<pb::Job> job = client.Watch(job_id, bar);
    bar.Finish();
    if (!job.ok()) return ReportError(job.status());
    std::printf("job %s %s (%d/%d tasks%s, %d retried)%s%s\n", job->id().c_str(),
                StateName(job->state()).c_str(), job->tasks_done(), job->tasks_total(),
                FramesDone(*job).c_str(), job->retries(), job->error().empty() ? "" : ": ",
                job->error().c_str());
    return job->state() == pb::Job::SUCCEEDED ? 0 : 1;
}

Command AddFetchCommand(CLI::App& app) {
    auto flags = std::make_shared<FarmFlags>();
    auto id = std::make_shared<std::string>();
    auto output = std::make_shared<OutputFlags>();
    auto preview = std::make_shared<bool>(false);
    CLI::App* cmd = app.add_subcommand(
        "fetch",
        "Download a job's OpenEXR result (the same channels and header as `lightfarm render`),\n"
        "or its PNG preview (-o out.png, or --png beside the EXR), made here as `render` makes\n"
        "it.");
    cmd->add_option("job", *id, "job id")->required();
    AddOutputFlags(cmd, *output);
    cmd->add_flag("--preview", *preview,
                  "a running job's tiles merged so far (unfinished tiles have fewer samples)");
    auto frames = std::make_shared<std::string>();
    cmd->add_option("--frames", *frames,
                    "a shot's frames to fetch, A-B[:STEP] or N (default: every finished one); "
                    "-o and --png then name each frame's file with a run of # for its number, "
                    "e.g. -o out_####.exr");
    AddServerOption(cmd, *flags);
    return {
        cmd, [flags, id, output, preview, frames] {
            absl::StatusOr<OutputPaths> paths = ResolveOutputPaths(*output);
            if (!paths.ok()) return ReportError(paths.status());
            absl::StatusOr<pb::Job> job = GetJob(*flags, *id);
            if (!job.ok()) return ReportError(job.status());
            if (job->frames_total() == 0) {
                if (!frames->empty()) {
                    return ReportError(absl::InvalidArgumentError(absl::StrCat(
                        "--frames: job ", *id, " is a still, not a shot; fetch it without")));
                }
                if (absl::Status s = FetchOutputs(*flags, *id, *paths, *output, *preview);
                    !s.ok()) {
                    return ReportError(s);
                }
                std::printf("job %s -> %s\n", id->c_str(), OutputNames(*paths).c_str());
                return 0;
            }
            absl::StatusOr<std::vector<int>> wanted =
                FramesToFetch(*job, *frames, *paths, *preview);
            if (!wanted.ok()) return ReportError(wanted.status());
            for (int f : *wanted) {
                OutputPaths frame_paths;
                for (auto [from, to] : {std::pair{&paths->exr, &frame_paths.exr},
                                        std::pair{&paths->png, &frame_paths.png},
                                        std::pair{&paths->false_color, &frame_paths.false_color}}) {
                    if (!from->empty()) *to = FramePath(*from, f);
                }
                if (absl::Status s = FetchOutputs(*flags, *id, frame_paths, *output, *preview, f);
                    !s.ok()) {
                    return ReportError(s);
                }
                std::printf("job %s frame %d -> %s\n", id->c_str(), f,
                            OutputNames(frame_paths).c_str());
            }
            return 0;
        }};
}

Command AddCancelCommand(CLI::App& app) {
    auto flags = std::make_shared<FarmFlags>();
    auto id = std::make_shared<std::string>();
    CLI::App* cmd = app.add_subcommand(
        "cancel", "Cancel a queued or running job; workers drop its tasks within a second.");
    cmd->add_option("job", *id, "job id")->required();
    AddServerOption(cmd, *flags);
    return {cmd, [flags, id] {
                pb::CancelJobRequest req;
                req.set_job_id(*id);
                pb::Job job;
                absl::Status s =
                    FarmClient(*flags).Call(&pb::JobService::Stub::CancelJob, req, &job);
                if (!s.ok()) return ReportError(s);
                std::printf("job %s %s\n", job.id().c_str(), StateName(job.state()).c_str());
                return 0;
            }};
}

Command AddPriorityCommand(CLI::App& app) {
    auto flags = std::make_shared<FarmFlags>();
    auto id = std::make_shared<std::string>();
    auto priority = std::make_shared<int>(0);
    CLI::App* cmd = app.add_subcommand(
        "priority",
        "Change a queued or running job's priority: higher runs first, from the next task on.");
    cmd->add_option("job", *id, "job id")->required();
    cmd->add_option("priority", *priority, "the new priority (submit's --priority)")->required();
    AddServerOption(cmd, *flags);
    return {cmd, [flags, id, priority] {
                pb::SetJobPriorityRequest req;
                req.set_job_id(*id);
                req.set_priority(*priority);
                pb::Job job;
                absl::Status s =
                    FarmClient(*flags).Call(&pb::JobService::Stub::SetJobPriority, req, &job);
                if (!s.ok()) return ReportError(s);
                std::printf("job %s priority %d\n", job.id().c_str(), job.priority());
                return 0;
            }};
}

Command AddDeleteCommand(CLI::App& app) {
    auto flags = std::make_shared<FarmFlags>();
    auto id = std::make_shared<std::string>();
    CLI::App* cmd = app.add_subcommand(
        "delete",
        "Delete an ended job and its result from the server (cancel a running one first).");
    cmd->add_option("job", *id, "job id")->required();
    AddServerOption(cmd, *flags);
    return {cmd, [flags, id] {
                pb::DeleteJobRequest req;
                req.set_job_id(*id);
                pb::DeleteJobResponse resp;
                absl::Status s =
                    FarmClient(*flags).Call(&pb::JobService::Stub::DeleteJob, req, &resp);
                if (!s.ok()) return ReportError(s);
                std::printf("job %s deleted\n", id->c_str());
                return 0;
            }};
}

namespace {

// The workers table (or JSON lines) of `workers`.
void PrintWorkers(const pb::ListWorkersResponse& resp, bool json) {
    if (json) {
        for (const pb::WorkerInfo& w : resp.workers()) PrintJson(w);
        return;
    }
    std::printf("%-28s %-20s %-24s %-30s %-8s %-22s %-20s %s\n", "WORKER", "NAME", "ADDRESS",
                "VERSION", "STATE", "TASK", "TAGS", "LAST-HEARTBEAT");
    for (const pb::WorkerInfo& w : resp.workers()) {
        const bool busy = !w.job_id().empty();
        const std::string tags =
            w.tags_size() > 0 ? LogSafe(absl::StrJoin(w.tags(), ","), 64) : "-";
        // Ids, names and versions come from the workers: escaped, so none can move the
        // terminal. The id first, as `tasks` names the worker: two workers of one host share
        // their name.
        std::printf("%-28s %-20s %-24s %-30s %-8s %-22s %-20s %.1f s ago\n",
                    LogSafe(w.id(), kWorkerIdShown).c_str(),
                    w.name().empty() ? "-" : LogSafe(w.name(), 64).c_str(),
                    LogSafe(w.address(), 64).c_str(), LogSafe(w.version(), 64).c_str(),
                    absl::AsciiStrToLower(pb::WorkerInfo::State_Name(w.state())).c_str(),
                    busy ? absl::StrCat(w.job_id(), "/", w.task_index()).c_str() : "-",
                    tags.c_str(), w.seconds_since_seen());
    }
}

}  // namespace

Command AddWorkersCommand(CLI::App& app) {
    auto flags = std::make_shared<FarmFlags>();
    CLI::App* cmd = app.add_subcommand(
        "workers",
        "List the workers the server knows: worker (the identity `tasks` and `logs` show), name\n"
        "(its --name, by default its host's), address, version, state (idle, busy, disabled,\n"
        "draining, drained, or offline: silent for a lease, listed until the server's\n"
        "--forget-workers-after), task, tags and seconds since each was last heard from.\n"
        "`workers disable|enable|drain NAME` (admins): a disabled worker takes no new task, its\n"
        "current one goes on; a drained one finishes its task, then takes none. NAME is a\n"
        "worker's name (every worker of that name) or id; the state survives server restarts.");
    auto json = std::make_shared<bool>(false);
    auto action = std::make_shared<std::string>();
    auto worker = std::make_shared<std::string>();
    cmd->add_option("action", *action, "disable, enable or drain")
        ->check(CLI::IsMember({"disable", "enable", "drain"}));
    cmd->add_option("worker", *worker, "the worker's name or id, with an action");
    AddJsonFlag(cmd, *json);
    AddServerOption(cmd, *flags);
    return {cmd, [flags, json, action, worker] {
                if (!action->empty() && worker->empty()) {
                    return ReportError(absl::InvalidArgumentError(
                        absl::StrCat("workers ", *action, ": name the worker (its name or id)")));
                }
                if (action->empty()) {
                    pb::ListWorkersRequest req;
                    pb::ListWorkersResponse resp;
                    absl::Status s =
                        FarmClient(*flags).Call(&pb::JobService::Stub::ListWorkers, req, &resp);
                    if (!s.ok()) return ReportError(s);
                    PrintWorkers(resp, *json);
                    return 0;
                }
                pb::SetWorkerStateRequest req;
                req.set_worker(*worker);
                req.set_control(*action == "disable" ? pb::SetWorkerStateRequest::DISABLE
                                : *action == "drain" ? pb::SetWorkerStateRequest::DRAIN
                                                     : pb::SetWorkerStateRequest::ENABLE);
                pb::SetWorkerStateResponse resp;
                absl::Status s =
                    FarmClient(*flags).Call(&pb::JobService::Stub::SetWorkerState, req, &resp);
                if (!s.ok()) return ReportError(s);
                pb::ListWorkersResponse shown;
                *shown.mutable_workers() = resp.workers();
                PrintWorkers(shown, *json);
                return 0;
            }};
}

namespace {

std::string TaskStateName(pb::TaskInfo::State s) {
    return absl::AsciiStrToLower(pb::TaskInfo::State_Name(s));
}

std::string TaskKindName(pb::TaskInfo::Kind k) {
    return absl::AsciiStrToLower(pb::TaskInfo::Kind_Name(k));
}

// "2026-11-26 23:40:01.123 task 3 #1 worker-a info     text", in the local time zone. The text
// was made safe by the server; the worker's id is escaped here.
void PrintLogLine(const pb::TaskLogLine& line) {
    const std::string time = absl::FormatTime(
        "%Y-%m-%d %H:%M:%E3S", absl::FromUnixMillis(line.unix_ms()), absl::LocalTimeZone());
    std::printf("%s task %d #%d %s %-8s %s\n", time.c_str(), line.task_index(), line.attempt(),
                LogSafe(line.worker(), kWorkerIdShown).c_str(), line.level().c_str(),
                line.text().c_str());
}

}  // namespace

Command AddTasksCommand(CLI::App& app) {
    auto flags = std::make_shared<FarmFlags>();
    auto id = std::make_shared<std::string>();
    auto json = std::make_shared<bool>(false);
    CLI::App* cmd = app.add_subcommand(
        "tasks",
        "List a job's tasks: state, kind, pixels, leases handed out, the worker of the last one,\n"
        "how long it ran (or runs so far), a done task's CPU seconds on its worker and its last\n"
        "error. An ended job's as the server recorded them when it ended.");
    cmd->add_option("job", *id, "job id")->required();
    AddJsonFlag(cmd, *json);
    AddServerOption(cmd, *flags);
    return {
        cmd, [flags, id, json] {
            pb::ListTasksRequest req;
            req.set_job_id(*id);
            pb::ListTasksResponse resp;
            absl::Status s = FarmClient(*flags).Call(&pb::JobService::Stub::ListTasks, req, &resp);
            if (!s.ok()) return ReportError(s);
            if (*json) {
                for (const pb::TaskInfo& t : resp.tasks()) PrintJson(t);
                return 0;
            }
            std::printf("%5s %-8s %-15s %-17s %-11s %8s %-28s %9s %9s  %s\n", "TASK", "STATE",
                        "KIND", "PIXELS", "FRAMES", "ATTEMPTS", "WORKER", "DURATION", "CPU",
                        "LAST-ERROR");
            for (const pb::TaskInfo& t : resp.tasks()) {
                const std::string pixels =
                    t.width() > 0 ? absl::StrCat(t.x(), ",", t.y(), " ", t.width(), "x", t.height())
                                  : "-";
                const std::string duration =
                    t.leased_unix_ms() > 0 ? absl::StrFormat("%.2f s", t.seconds()) : "-";
                // A task's frames: one, or a chunk's first-last; "-" for a still's.
                const std::string frames =
                    t.frames().empty() ? "-"
                    : t.frames_size() == 1
                        ? absl::StrCat(t.frames(0))
                        : absl::StrCat(t.frames(0), "-", t.frames(t.frames_size() - 1));
                // The worker's CPU seconds over a done task's render (issue 30's history).
                const std::string cpu = t.state() == pb::TaskInfo::DONE && t.render_seconds() > 0
                                            ? absl::StrFormat("%.2f s", t.cpu_seconds())
                                            : "-";
                std::printf("%5d %-8s %-15s %-17s %-11s %8d %-28s %9s %9s  %s\n", t.index(),
                            TaskStateName(t.state()).c_str(), TaskKindName(t.kind()).c_str(),
                            pixels.c_str(), frames.c_str(), t.attempts(),
                            t.worker().empty() ? "-" : LogSafe(t.worker(), kWorkerIdShown).c_str(),
                            duration.c_str(), cpu.c_str(), LogSafe(t.last_error(), 200).c_str());
            }
            return 0;
        }};
}

Command AddLogsCommand(CLI::App& app) {
    auto flags = std::make_shared<FarmFlags>();
    auto id = std::make_shared<std::string>();
    auto task = std::make_shared<int>(-1);
    auto follow = std::make_shared<bool>(false);
    auto json = std::make_shared<bool>(false);
    CLI::App* cmd = app.add_subcommand(
        "logs",
        "Print what workers logged while running a job's tasks, in the order the server took\n"
        "the lines: time, task, attempt (#1 is the first lease), worker, level, text. The server\n"
        "keeps each task's most recent lines (docs/farm.md, Tasks and logs).");
    cmd->add_option("job", *id, "job id")->required();
    cmd->add_option("--task", *task, "only this task's lines (its index, as `lightfarm tasks`)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_flag("--follow,-f", *follow,
                  "keep printing new lines (polling twice a second) until the job ends; exit 0");
    AddJsonFlag(cmd, *json);
    AddServerOption(cmd, *flags);
    AddRetryOption(cmd, *flags);
    return {cmd, [flags, id, task, follow, json] {
                FarmClient client(*flags);
                pb::GetTaskLogsRequest req;
                req.set_job_id(*id);
                if (*task >= 0) req.set_task_index(*task);
                while (true) {
                    pb::GetTaskLogsResponse resp;
                    const absl::Status s = client.CallRetrying(
                        "logs " + *id, &pb::JobService::Stub::GetTaskLogs, req, &resp);
                    if (!s.ok()) return ReportError(s);
                    for (const pb::TaskLogLine& line : resp.lines()) {
                        if (*json) {
                            PrintJson(line);
                        } else {
                            PrintLogLine(line);
                        }
                    }
                    std::fflush(stdout);
                    req.set_after_seq(resp.next_seq());
                    if (resp.job_ended()) return 0;
                    if (!resp.lines().empty()) continue;  // more may be kept: the next page
                    if (!*follow) return 0;
                    absl::SleepFor(absl::Milliseconds(500));
                }
            }};
}

namespace {

// The stats tables (issue 30), each column as wide as its widest cell.
void PrintStats(const pb::GetStatsResponse& stats, const std::string& since) {
    std::printf("since %s\n",
                stats.since_unix_ms() > 0
                    ? absl::StrCat(LocalTime(stats.since_unix_ms()), " (", since, ")").c_str()
                    : "the start of the history kept");
    const auto hours = [](double seconds) { return absl::StrFormat("%.3f", seconds / 3600); };
    const auto print = [](const std::vector<std::vector<std::string>>& rows) {
        std::vector<size_t> widths(rows.front().size(), 0);
        for (const auto& row : rows) {
            for (size_t i = 0; i < row.size(); ++i) widths[i] = std::max(widths[i], row[i].size());
        }
        for (const auto& row : rows) {
            std::string line = absl::StrFormat("%-*s", int(widths[0]), row[0]);
            for (size_t i = 1; i < row.size(); ++i) {
                absl::StrAppend(&line, absl::StrFormat("  %*s", int(widths[i]), row[i]));
            }
            std::printf("%s\n", line.c_str());
        }
    };
    std::vector<std::vector<std::string>> owners = {{"OWNER", "SUCCEEDED", "FAILED", "CANCELLED",
                                                     "ACTIVE", "TASKS", "SAMPLES", "CPU-HOURS",
                                                     "RENDER-HOURS"}};
    for (const pb::OwnerStats& o : stats.owners()) {
        owners.push_back({o.owner().empty() ? "-" : LogSafe(o.owner(), kWorkerIdShown),
                          absl::StrCat(o.jobs_succeeded()), absl::StrCat(o.jobs_failed()),
                          absl::StrCat(o.jobs_cancelled()), absl::StrCat(o.jobs_active()),
                          absl::StrCat(o.tasks()), absl::StrCat(o.samples()),
                          hours(o.cpu_seconds()), hours(o.render_seconds())});
    }
    print(owners);
    std::printf("\n");
    std::vector<std::vector<std::string>> workers = {
        {"WORKER", "TASKS", "FAILURES", "CPU-HOURS", "RENDER-HOURS"}};
    for (const pb::WorkerStats& w : stats.workers()) {
        workers.push_back({LogSafe(w.worker(), kWorkerIdShown), absl::StrCat(w.tasks()),
                           absl::StrCat(w.failures()), hours(w.cpu_seconds()),
                           hours(w.render_seconds())});
    }
    print(workers);
}

}  // namespace

Command AddStatsCommand(CLI::App& app) {
    auto flags = std::make_shared<FarmFlags>();
    auto since = std::make_shared<std::string>();
    auto owner = std::make_shared<std::string>();
    auto json = std::make_shared<bool>(false);
    CLI::App* cmd = app.add_subcommand(
        "stats",
        "The farm's history (kept across restarts and job deletions, for 400 days): per owner,\n"
        "jobs that ended by final state and those active now, tasks, samples, CPU and render\n"
        "hours; per worker, tasks, failures, CPU and render hours. An admin sees everyone's, a\n"
        "submitter their own jobs' (docs/farm.md, History).");
    cmd->add_option("--since", *since,
                    "only work that ended since: 7d, 24h, 30m, 45s ago, a date 2026-11-01 (UTC) "
                    "or a time 2026-11-01T08:00:00Z; default: all the history kept");
    cmd->add_option("--owner", *owner, "only this owner's jobs (an admin's choice)");
    cmd->add_flag("--json", *json,
                  "one JSON object instead of the tables: lightfarm.v1.GetStatsResponse with "
                  "proto field names (docs/farm.md, History)");
    AddServerOption(cmd, *flags);
    return {cmd, [flags, since, owner, json] {
                pb::GetStatsRequest req;
                if (!since->empty()) {
                    absl::StatusOr<absl::Time> start = ParseSince(*since, absl::Now());
                    if (!start.ok()) return ReportError(start.status());
                    req.set_since_unix_ms(absl::ToUnixMillis(*start));
                }
                req.set_owner(*owner);
                pb::GetStatsResponse resp;
                absl::Status s =
                    FarmClient(*flags).Call(&pb::JobService::Stub::GetStats, req, &resp);
                if (!s.ok()) return ReportError(s);
                if (*json) {
                    PrintJson(resp);
                } else {
                    PrintStats(resp, *since);
                }
                return 0;
            }};
}

}  // namespace lf
