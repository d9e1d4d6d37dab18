// The farm subcommands of `lightfarm`: submit, list, status, watch, fetch, cancel, priority,
// delete, workers, tasks and logs, each a call to lightfarm-server's JobService. All protobuf
// handling of the client is in this file.
#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "adaptive_flags.h"
#include "command.h"
#include "lf/core/image_io.h"
#include "lf/core/log.h"
#include "lf/core/scene_loader.h"
#include "lf/job/digest.h"
#include "lf/job/job_spec.h"
#include "lf/job/plan.h"
#include "lf/job/scene_files.h"
#include "lf/wire/conversions.h"
#include "lightfarm/v1/job_service.grpc.pb.h"
#include "method_flags.h"
#include "output_flags.h"
#include "photon_flags.h"
#include "progress_bar.h"
#include "proto/channel.h"
#include "proto/channel_flags.h"
#include "proto/grpc_status.h"
#include "radiosity_flags.h"
#include "sample_flags.h"
#include "scene_flags.h"

namespace lf {

namespace fs = std::filesystem;
namespace pb = lightfarm::v1;

namespace {

constexpr size_t kChunkBytes = 1 << 20;

struct FarmFlags {
    ChannelOptions channel{.address = "127.0.0.1:7070"};
    double retry_seconds = 60;  // how long submit and watch ride out an unreachable server
};

// --server and the TLS and token flags; files they name are checked once the command line is
// parsed, so that a wrong path is said before any work.
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

// Waits between attempts to reach a server that is down: 0.25 s, doubling up to 5 s, until the
// budget is spent, saying on stderr what it waits for.
class Backoff {
  public:
    explicit Backoff(const FarmFlags& flags) : budget_(absl::Seconds(flags.retry_seconds)) {}

    // False when the budget is spent: give up with `why`.
    bool Wait(const std::string& what, const absl::Status& why) {
        if (waited_ + delay_ > budget_) return false;
        std::fprintf(stderr, "lightfarm: %s: %s; retrying in %.2g s\n", what.c_str(),
                     std::string(why.message()).c_str(), absl::ToDoubleSeconds(delay_));
        absl::SleepFor(delay_);
        waited_ += delay_;
        delay_ = std::min(2 * delay_, kMaxDelay);
        return true;
    }
    // The server answered: a later outage gets the whole budget again.
    void Reset() {
        waited_ = absl::ZeroDuration();
        delay_ = kFirstDelay;
    }

  private:
    static constexpr absl::Duration kFirstDelay = absl::Milliseconds(250);
    static constexpr absl::Duration kMaxDelay = absl::Seconds(5);
    absl::Duration budget_;
    absl::Duration waited_ = absl::ZeroDuration();
    absl::Duration delay_ = kFirstDelay;
};

// A new channel: after an outage, retries take a new one, as a channel that failed to connect
// fails calls fast for a while after the server is back.
std::unique_ptr<pb::JobService::Stub> Connect(const FarmFlags& flags) {
    absl::StatusOr<std::shared_ptr<grpc::Channel>> channel = OpenChannel(flags.channel);
    if (!channel.ok()) {
        // The files were readable when the command line was parsed (AddServerOption): one
        // removed since leaves nothing to retry with.
        std::fprintf(stderr, "lightfarm: error: %s\n",
                     std::string(channel.status().message()).c_str());
        std::exit(2);
    }
    return pb::JobService::NewStub(*channel);
}

// The server's own words, with where it was asked when it could not be reached.
absl::Status CallStatus(const grpc::Status& s, const FarmFlags& flags) {
    // gRPC reports a TLS handshake that failed on a certificate or on a plain-text peer as
    // UNAVAILABLE, like a server that is down; retrying cannot help, so it is said at once.
    if (s.error_code() == grpc::StatusCode::UNAVAILABLE &&
        absl::StrContains(s.error_message(), "SSL_ERROR_SSL")) {
        return absl::FailedPreconditionError(absl::StrCat(
            "TLS handshake with server ", flags.channel.address, " failed (", s.error_message(),
            "): check --tls-ca, the server's certificate names, and --tls-cert/--tls-key if the "
            "server asks for client certificates"));
    }
    if (s.error_code() == grpc::StatusCode::UNAVAILABLE) {
        return absl::UnavailableError(
            absl::StrCat("server ", flags.channel.address, " not reachable: ", s.error_message()));
    }
    return FromGrpcStatus(s);
}

void AddJsonFlag(CLI::App* cmd, bool& json) {
    cmd->add_flag("--json", json,
                  "one JSON object a line instead of the table: the wire message's fields "
                  "(lightfarm.v1, proto field names, every field present)");
}

// The message as one line of JSON, as protobuf's own mapping writes it (strings escaped, so no
// name a worker or submitter chose can move the terminal).
void PrintJson(const google::protobuf::Message& message) {
    google::protobuf::util::JsonPrintOptions options;
    options.always_print_primitive_fields = true;
    options.preserve_proto_field_names = true;
    std::string line;
    if (google::protobuf::util::MessageToJsonString(message, &line, options).ok()) {
        std::printf("%s\n", line.c_str());
    }
}

std::string StateName(pb::Job::State s) { return absl::AsciiStrToLower(pb::Job::State_Name(s)); }

bool IsFinal(pb::Job::State s) {
    return s == pb::Job::SUCCEEDED || s == pb::Job::FAILED || s == pb::Job::CANCELLED;
}

absl::StatusOr<std::string> ReadFile(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return absl::NotFoundError(path.string() + ": cannot be read");
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

// Loads the scene here, as `render` would, through a reader that records every file the loader
// reads by the name it asks for (the name the server and workers look it up by): exactly the
// files the farm needs (meshes, MTL files, included glTFs, their buffers and images), whatever
// the format. A scene that does not load is refused here, with the loader's message, before
// anything is uploaded. Returns the files' contents by name.
absl::StatusOr<std::map<std::string, std::string>> ReadSceneFiles(const fs::path& scene_path,
                                                                  const std::string& scene_text,
                                                                  const SceneOptions& options) {
    std::map<std::string, std::string> read;
    const fs::path parent = scene_path.parent_path();
    const SceneFileReader beside = ReadBeside(parent.empty() ? "." : parent.string());
    const SceneFileReader recording = [&](const std::string& name) {
        absl::StatusOr<std::string> bytes = beside(name);
        if (bytes.ok()) read[name] = *bytes;
        return bytes;
    };
    absl::StatusOr<Scene> scene = ParseScene(scene_text, scene_path.string(), recording, options);
    if (!scene.ok()) return scene.status();
    return read;
}

struct LocalFile {
    pb::SceneFile ref;
};

// Uploads whose bytes add up to this show a progress bar (on a terminal).
constexpr uint64_t kProgressBarBytes = uint64_t(16) << 20;

// Sends what the server lacks of one blob: from where its bytes end (BlobUploadOffset), so an
// upload that broke resumes instead of starting over. `sent` counts the bytes the server holds
// of the blobs uploaded so far, of `total`, for `bar` (null: no bar).
absl::Status Upload(pb::JobService::Stub& stub, const LocalFile& file, const std::string& content,
                    const FarmFlags& flags, uint64_t& sent, uint64_t total, ProgressBar* bar) {
    auto failed = [&](const absl::Status& s) {
        return absl::Status(s.code(), absl::StrCat(file.ref.path(), ": upload: ", s.message()));
    };
    pb::BlobUploadOffsetRequest where;
    where.set_hash(file.ref.hash());
    where.set_size(file.ref.size());
    pb::BlobUploadOffsetResponse held;
    const grpc::Status asked =
        stub.BlobUploadOffset(ContextWithDeadline(absl::Seconds(10)).get(), where, &held);
    // A server of an earlier version, without the call, takes whole uploads only.
    if (!asked.ok() && asked.error_code() != grpc::StatusCode::UNIMPLEMENTED) {
        return failed(CallStatus(asked, flags));
    }
    const size_t offset = std::min<uint64_t>(held.offset(), content.size());
    if (offset > 0 && offset < content.size()) {
        std::fprintf(stderr, "lightfarm: %s: the server holds %zu of %zu bytes; sending the rest\n",
                     file.ref.path().c_str(), offset, content.size());
    }
    sent += offset;
    if (offset == content.size()) return absl::OkStatus();

    const auto context = ContextWithDeadline(absl::Minutes(10));
    pb::UploadBlobResponse response;
    std::unique_ptr<grpc::ClientWriter<pb::UploadBlobRequest>> writer =
        stub.UploadBlob(context.get(), &response);
    pb::UploadBlobRequest chunk;
    chunk.set_hash(file.ref.hash());
    chunk.set_size(file.ref.size());
    chunk.set_offset(offset);
    size_t at = offset;
    do {
        const size_t n = std::min(kChunkBytes, content.size() - at);
        chunk.set_data(content.data() + at, n);
        if (!writer->Write(chunk)) break;
        at += n;
        sent += n;
        if (bar) bar->Update(sent, total);
        chunk.clear_hash();
        chunk.clear_size();
        chunk.clear_offset();
    } while (at < content.size());
    writer->WritesDone();
    if (absl::Status s = CallStatus(writer->Finish(), flags); !s.ok()) return failed(s);
    return absl::OkStatus();
}

// Uploads the blobs the server lacks and submits the job: one attempt.
absl::StatusOr<std::string> SubmitOnce(pb::JobService::Stub& stub, const FarmFlags& flags,
                                       const std::vector<LocalFile>& files,
                                       const std::map<std::string, std::string>& contents,
                                       const pb::SubmitJobRequest& req) {
    pb::MissingBlobsRequest missing_req;
    for (const auto& [hash, content] : contents) missing_req.add_hashes(hash);
    pb::MissingBlobsResponse missing;
    if (absl::Status s = CallStatus(
            stub.MissingBlobs(ContextWithDeadline(absl::Seconds(10)).get(), missing_req, &missing),
            flags);
        !s.ok()) {
        return s;
    }
    std::vector<const LocalFile*> uploads;
    uint64_t total = 0, sent = 0;
    for (const std::string& hash : missing.hashes()) {
        for (const LocalFile& f : files) {
            if (f.ref.hash() != hash) continue;
            uploads.push_back(&f);
            total += f.ref.size();
            break;
        }
    }
    std::optional<ProgressBar> bar;
    if (total >= kProgressBarBytes) bar.emplace("upload");
    for (const LocalFile* f : uploads) {
        const absl::Status s =
            Upload(stub, *f, contents.at(f->ref.hash()), flags, sent, total, bar ? &*bar : nullptr);
        if (!s.ok()) {
            if (bar) bar->Finish();  // the bar's line ends before the error's
            return s;
        }
    }
    if (bar) bar->Finish();

    pb::SubmitJobResponse resp;
    // The server loads the scene to check it, which takes a while for large meshes.
    if (absl::Status s = CallStatus(
            stub.SubmitJob(ContextWithDeadline(absl::Minutes(2)).get(), req, &resp), flags);
        !s.ok()) {
        return s;
    }
    return resp.job_id();
}

struct SubmitOptions {
    FarmFlags farm;
    std::string scene_path;
    JobSpec spec;  // the scene and files are filled in by Submit
};

absl::StatusOr<std::string> Submit(const SubmitOptions& o) {
    const fs::path scene_path(o.scene_path);
    absl::StatusOr<std::string> scene_text = ReadFile(scene_path);
    if (!scene_text.ok()) return scene_text.status();
    absl::StatusOr<std::map<std::string, std::string>> read =
        ReadSceneFiles(scene_path, *scene_text, o.spec.scene_options);
    if (!read.ok()) return read.status();

    std::vector<LocalFile> files;
    std::map<std::string, std::string> contents;  // by hash
    auto add = [&](const std::string& name, std::string content) -> absl::Status {
        if (absl::Status s = CheckScenePath(name); !s.ok()) {
            return absl::InvalidArgumentError(absl::StrCat(o.scene_path, ": ", s.message()));
        }
        LocalFile f;
        f.ref.set_path(name);
        f.ref.set_hash(Sha256Hex(content));
        f.ref.set_size(content.size());
        contents[f.ref.hash()] = std::move(content);
        files.push_back(std::move(f));
        return absl::OkStatus();
    };
    if (absl::Status s = add(scene_path.filename().string(), *scene_text); !s.ok()) {
        return s;
    }
    for (auto& [name, content] : *read) {
        if (absl::Status s = add(name, std::move(content)); !s.ok()) return s;
    }

    JobSpec spec = o.spec;
    std::vector<BlobRef> refs;
    for (const LocalFile& f : files) refs.push_back(FromProto(f.ref));
    spec.scene = refs[0];
    spec.files.assign(refs.begin() + 1, refs.end());
    if (spec.name.empty()) spec.name = scene_path.filename().string();
    // The same id on every attempt: a retry after a lost answer (the server restarting, say)
    // gets the job of the first attempt.
    spec.request_id = Sha256Hex(
        absl::StrCat(absl::ToUnixNanos(absl::Now()), "/", ::getpid(), "/", scene_path.string()));
    pb::SubmitJobRequest req;
    ToProto(spec, &req);

    Backoff backoff(o.farm);
    while (true) {
        absl::StatusOr<std::string> id = SubmitOnce(*Connect(o.farm), o.farm, files, contents, req);
        // Aborted: another client was uploading one of the blobs; the retry resumes from its
        // bytes, or finds the blob stored.
        const bool transient = absl::IsUnavailable(id.status()) || absl::IsAborted(id.status());
        if (!transient || !backoff.Wait("submit", id.status())) {
            return id;
        }
    }
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

std::string Progress(const pb::Job& job) {
    return absl::StrCat(job.tasks_done(), "/", job.tasks_total());
}

void PrintJob(const pb::Job& job) {
    const int64_t now = absl::ToUnixMillis(absl::Now());
    auto seconds = [](int64_t from, int64_t to) { return double(to - from) / 1000.0; };
    std::printf("job %s: %s\n", job.id().c_str(), StateName(job.state()).c_str());
    std::printf("  name      %s\n", job.name().c_str());
    if (!job.owner().empty()) std::printf("  owner     %s\n", job.owner().c_str());
    std::printf("  method    %s\n",
                job.params().method().empty() ? "path" : job.params().method().c_str());
    std::printf("  image     %dx%d, %llu spp, seed %llu, max depth %d, tile %d, %d passes\n",
                job.width(), job.height(), (unsigned long long)job.params().spp(),
                (unsigned long long)job.params().seed(), job.params().max_depth(),
                job.params().tile(), job.params().passes());
    JobSpec spec;
    FromProto(job.params(), &spec);
    // Radiosity samples no lights: its light strategy would say nothing.
    std::printf("  sampling  %s sampler%s\n", SamplerTypeName(spec.sampler),
                FindMethod(spec.method) == Method::kRadiosity
                    ? ""
                    : absl::StrCat(", ", LightStrategyName(spec.light_strategy), " light sampling")
                          .c_str());
    if (job.params().target_error() > 0 || job.params().time_limit_seconds() > 0) {
        std::printf("  adaptive  target error %g, time limit %g s, at most %llu spp\n",
                    job.params().target_error(), job.params().time_limit_seconds(),
                    (unsigned long long)job.params().max_spp());
    }
    std::printf("  priority  %d\n", job.priority());
    std::printf("  tasks     %s done, %d running, %d retried, %d leased\n", Progress(job).c_str(),
                job.tasks_running(), job.retries(), job.tasks_leased());
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
    std::string when = absl::StrCat("  submitted ", LocalTime(job.submitted_unix_ms()));
    if (job.started_unix_ms() > 0)
        absl::StrAppend(&when, ", started ", LocalTime(job.started_unix_ms()));
    if (job.finished_unix_ms() > 0) {
        absl::StrAppend(&when, ", ended ", LocalTime(job.finished_unix_ms()));
    }
    std::printf("%s\n", when.c_str());
    // A failed job's error names the failing task; its last error says what that one did.
    if ((!IsFinal(job.state()) || job.state() == pb::Job::FAILED) && !job.last_error().empty()) {
        std::printf("  last error  %s\n", job.last_error().c_str());
    }
    if (!job.error().empty()) std::printf("  error     %s\n", job.error().c_str());
}

absl::StatusOr<pb::Job> GetJob(const FarmFlags& flags, const std::string& id) {
    pb::GetJobRequest req;
    req.set_job_id(id);
    pb::Job job;
    absl::Status s = CallStatus(
        Connect(flags)->GetJob(ContextWithDeadline(absl::Seconds(10)).get(), req, &job), flags);
    if (!s.ok()) return s;
    return job;
}

// Follows the job until it ends. Each call has a deadline; the watch goes on across them and
// across a server outage of up to --retry-seconds.
absl::StatusOr<pb::Job> Watch(const FarmFlags& flags, const std::string& id, ProgressBar& bar) {
    std::unique_ptr<pb::JobService::Stub> stub = Connect(flags);
    pb::WatchJobRequest req;
    req.set_job_id(id);
    pb::Job job;
    Backoff backoff(flags);
    while (true) {
        const auto context = ContextWithDeadline(absl::Minutes(1));
        std::unique_ptr<grpc::ClientReader<pb::Job>> reader = stub->WatchJob(context.get(), req);
        while (reader->Read(&job)) {
            backoff.Reset();
            bar.Update(size_t(job.tasks_done()), size_t(std::max(1, job.tasks_total())));
            if (IsFinal(job.state())) return job;
        }
        const grpc::Status s = reader->Finish();
        if (s.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED) continue;
        if (const absl::Status status = CallStatus(s, flags);
            absl::IsUnavailable(status) && backoff.Wait("watch " + id, status)) {
            stub = Connect(flags);
            continue;
        }
        if (!s.ok()) return CallStatus(s, flags);
        if (IsFinal(job.state())) return job;
    }
}

absl::Status Fetch(const FarmFlags& flags, const std::string& id, const std::string& out,
                   bool preview) {
    pb::FetchResultRequest req;
    req.set_job_id(id);
    req.set_preview(preview);
    const auto context = ContextWithDeadline(absl::Minutes(30));
    std::unique_ptr<grpc::ClientReader<pb::Chunk>> reader =
        Connect(flags)->FetchResult(context.get(), req);
    // Written beside the target and renamed, so a failed fetch leaves no half file.
    const std::string temp = out + ".part";
    std::ofstream file(temp, std::ios::binary);
    if (!file) return absl::PermissionDeniedError(out + ": cannot write here");
    pb::Chunk chunk;
    while (reader->Read(&chunk)) {
        file.write(chunk.data().data(), std::streamsize(chunk.data().size()));
    }
    file.close();
    std::error_code ec;
    if (absl::Status s = CallStatus(reader->Finish(), flags); !s.ok() || !file) {
        fs::remove(temp, ec);
        return s.ok() ? absl::InternalError(out + ": write failed") : s;
    }
    fs::rename(temp, out, ec);
    if (ec) return absl::InternalError(out + ": " + ec.message());
    return absl::OkStatus();
}

// The job's EXR at paths.exr, and its preview at paths.png, made here from the EXR (fetched into
// a temporary file when -o names only the PNG).
absl::Status FetchOutputs(const FarmFlags& flags, const std::string& id, const OutputPaths& paths,
                          const PngOptions& preview_options, bool preview) {
    if (absl::Status s = CheckWritable(paths.png); !s.ok()) return s;
    const std::string exr = paths.exr.empty() ? paths.png + ".exr.part" : paths.exr;
    if (absl::Status s = Fetch(flags, id, exr, preview); !s.ok()) return s;
    if (paths.png.empty()) return absl::OkStatus();
    absl::StatusOr<ExrFile> file = ReadExr(exr);
    absl::Status written =
        file.ok() ? WritePng(paths.png, file->image, preview_options) : file.status();
    std::error_code ignored;  // a temporary file left behind is harmless
    if (paths.exr.empty()) fs::remove(exr, ignored);
    return written;
}

}  // namespace

Command AddSubmitCommand(CLI::App& app) {
    auto o = std::make_shared<SubmitOptions>();
    CLI::App* cmd = app.add_subcommand(
        "submit",
        "Send a scene to a lightfarm-server as a job and print its id (the last line).\n"
        "The scene file and every file it names (meshes; wherever `render` would find them)\n"
        "are uploaded, and the farm reads only those; files the\n"
        "server already has are not sent again. Same settings give the same bits as\n"
        "`lightfarm render`, whatever the tile size, passes or workers.");
    cmd->add_option("scene", o->scene_path, "scene file (JSON, .gltf or .glb)")
        ->required()
        ->check(CLI::ExistingFile);
    AddSceneFlags(cmd, o->spec.scene_options);
    AddServerOption(cmd, o->farm);
    AddRetryOption(cmd, o->farm);
    cmd->add_option("--spp", o->spec.plan.spp, "samples per pixel")
        ->capture_default_str()
        ->check(CLI::Range(uint64_t(1), kMaxSpp));
    cmd->add_option("--seed", o->spec.seed, "random seed")->capture_default_str();
    cmd->add_option("--max-depth", o->spec.max_depth,
                    "most bounces per path; -1 = unlimited (Russian roulette ends paths)")
        ->capture_default_str()
        ->check(CLI::Range(-1, kMaxDepthLimit));
    cmd->add_option("--tile", o->spec.plan.tile, "tile side in pixels")
        ->capture_default_str()
        ->check(CLI::Range(1, kMaxFarmTile));
    cmd->add_option("--passes", o->spec.plan.passes,
                    "sample passes per tile; each pass of each tile is one task")
        ->capture_default_str()
        ->check(CLI::Range(1, kMaxPasses));
    AddSampleFlags(cmd, o->spec.sampler, o->spec.light_strategy, o->spec.clamp, o->spec.aovs);
    AddAdaptiveFlags(cmd, o->spec.adaptive);
    cmd->add_option("--priority", o->spec.priority, "higher runs first; equal: oldest first")
        ->capture_default_str();
    cmd->add_option("--name", o->spec.name, "job name (default: the scene file's name)");
    cmd->add_option("--method", o->spec.method,
                    "path, radiosity (Lambertian scenes; same bits as `lightfarm render "
                    "--method radiosity` with the same options), whitted (direct light and "
                    "specular chains only, a preview), or a frame method: light (light tracing), "
                    "bdpt (bidirectional path tracing), ppm (progressive photon mapping). Every "
                    "method gives the bits of `lightfarm render` with the same options; the "
                    "frame methods take no --aov nor adaptive sampling")
        ->capture_default_str()
        ->check([](const std::string& m) { return MethodFlagError(m, false); });
    AddPhotonFlags(cmd, o->spec.ppm);
    AddRadiosityFlags(cmd, o->spec.radiosity);
    cmd->add_option("--sweep-tasks", o->spec.radiosity.sweep_tasks,
                    "--solver jacobi: patch-group tasks per sweep; each worker computes the "
                    "form-factor rows of its groups once and keeps them. Gauss-Seidel and "
                    "shooting update one group after another, so with them every worker "
                    "solves the whole system before rendering display tiles")
        ->group("Radiosity")
        ->capture_default_str()
        ->check(CLI::Range(1, kMaxSweepTasks));
    return {cmd, [cmd, o] {
                if (absl::Status s = CheckRadiosityFlagsApply(*cmd, o->spec.method); !s.ok()) {
                    return ReportError(s);
                }
                if (absl::Status s = CheckPhotonFlagsApply(*cmd, o->spec.method); !s.ok()) {
                    return ReportError(s);
                }
                absl::StatusOr<std::string> id = Submit(*o);
                if (!id.ok()) return ReportError(id.status());
                std::printf("%s\n", id->c_str());
                return 0;
            }};
}

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
                const std::unique_ptr<pb::JobService::Stub> stub = Connect(*flags);
                pb::ListJobsRequest req;
                int listed = 0;
                if (!*json) {
                    std::printf("%-16s %-10s %-12s %-9s %8s %11s %9s %-19s %8s  %s\n", "JOB",
                                "STATE", "OWNER", "METHOD", "PRIORITY", "TASKS", "SPP", "SUBMITTED",
                                "TIME", "NAME");
                }
                do {
                    req.set_page_size(*limit > 0 ? std::min(kPage, *limit - listed) : kPage);
                    pb::ListJobsResponse resp;
                    absl::Status s = CallStatus(
                        stub->ListJobs(ContextWithDeadline(absl::Seconds(10)).get(), req, &resp),
                        *flags);
                    if (!s.ok()) return ReportError(s);
                    for (const pb::Job& job : resp.jobs()) {
                        if (*json) {
                            PrintJson(job);
                            continue;
                        }
                        std::printf(
                            "%-16s %-10s %-12s %-9s %8d %11s %9llu %-19s %8s  %s\n",
                            job.id().c_str(), StateName(job.state()).c_str(),
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
                absl::StatusOr<pb::Job> job = GetJob(*flags, *id);
                if (!job.ok()) return ReportError(job.status());
                if (*json) {
                    PrintJson(*job);
                } else {
                    PrintJob(*job);
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
                ProgressBar bar(*id);
                absl::StatusOr<pb::Job> job = Watch(*flags, *id, bar);
                bar.Finish();
                if (!job.ok()) return ReportError(job.status());
                std::printf("job %s %s (%s tasks, %d retried)%s%s\n", job->id().c_str(),
                            StateName(job->state()).c_str(), Progress(*job).c_str(), job->retries(),
                            job->error().empty() ? "" : ": ", job->error().c_str());
                return job->state() == pb::Job::SUCCEEDED ? 0 : 1;
            }};
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
    AddServerOption(cmd, *flags);
    return {cmd, [flags, id, output, preview] {
                absl::StatusOr<OutputPaths> paths = ResolveOutputPaths(*output);
                if (!paths.ok()) return ReportError(paths.status());
                if (absl::Status s = FetchOutputs(*flags, *id, *paths, output->preview, *preview);
                    !s.ok()) {
                    return ReportError(s);
                }
                std::printf("job %s -> %s\n", id->c_str(), OutputNames(*paths).c_str());
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
    return {
        cmd, [flags, id] {
            pb::CancelJobRequest req;
            req.set_job_id(*id);
            pb::Job job;
            absl::Status s = CallStatus(
                Connect(*flags)->CancelJob(ContextWithDeadline(absl::Seconds(10)).get(), req, &job),
                *flags);
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
                    CallStatus(Connect(*flags)->SetJobPriority(
                                   ContextWithDeadline(absl::Seconds(10)).get(), req, &job),
                               *flags);
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
                    CallStatus(Connect(*flags)->DeleteJob(
                                   ContextWithDeadline(absl::Seconds(10)).get(), req, &resp),
                               *flags);
                if (!s.ok()) return ReportError(s);
                std::printf("job %s deleted\n", id->c_str());
                return 0;
            }};
}

Command AddWorkersCommand(CLI::App& app) {
    auto flags = std::make_shared<FarmFlags>();
    CLI::App* cmd = app.add_subcommand(
        "workers",
        "List the workers the server heard from within a lease: name, address, version, state,\n"
        "task and seconds since each was last heard from.");
    auto json = std::make_shared<bool>(false);
    AddJsonFlag(cmd, *json);
    AddServerOption(cmd, *flags);
    return {cmd, [flags, json] {
                pb::ListWorkersRequest req;
                pb::ListWorkersResponse resp;
                absl::Status s =
                    CallStatus(Connect(*flags)->ListWorkers(
                                   ContextWithDeadline(absl::Seconds(10)).get(), req, &resp),
                               *flags);
                if (!s.ok()) return ReportError(s);
                if (*json) {
                    for (const pb::WorkerInfo& w : resp.workers()) PrintJson(w);
                    return 0;
                }
                std::printf("%-20s %-24s %-30s %-5s %-22s %s\n", "NAME", "ADDRESS", "VERSION",
                            "STATE", "TASK", "LAST-HEARTBEAT");
                for (const pb::WorkerInfo& w : resp.workers()) {
                    const bool busy = w.state() == pb::WorkerInfo::BUSY;
                    // Names and versions come from the workers: escaped, so none can move the
                    // terminal.
                    std::printf("%-20s %-24s %-30s %-5s %-22s %.1f s ago\n",
                                LogSafe(w.name().empty() ? w.id() : w.name(), 64).c_str(),
                                LogSafe(w.address(), 64).c_str(), LogSafe(w.version(), 64).c_str(),
                                busy ? "busy" : "idle",
                                busy ? absl::StrCat(w.job_id(), "/", w.task_index()).c_str() : "-",
                                w.seconds_since_seen());
                }
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
                LogSafe(line.worker(), 64).c_str(), line.level().c_str(), line.text().c_str());
}

}  // namespace

Command AddTasksCommand(CLI::App& app) {
    auto flags = std::make_shared<FarmFlags>();
    auto id = std::make_shared<std::string>();
    auto json = std::make_shared<bool>(false);
    CLI::App* cmd = app.add_subcommand(
        "tasks",
        "List a job's tasks: state, kind, pixels, leases handed out, the worker of the last one,\n"
        "how long it ran (or runs so far) and its last error. An ended job's as the server\n"
        "recorded them when it ended.");
    cmd->add_option("job", *id, "job id")->required();
    AddJsonFlag(cmd, *json);
    AddServerOption(cmd, *flags);
    return {cmd, [flags, id, json] {
                pb::ListTasksRequest req;
                req.set_job_id(*id);
                pb::ListTasksResponse resp;
                absl::Status s =
                    CallStatus(Connect(*flags)->ListTasks(
                                   ContextWithDeadline(absl::Seconds(10)).get(), req, &resp),
                               *flags);
                if (!s.ok()) return ReportError(s);
                if (*json) {
                    for (const pb::TaskInfo& t : resp.tasks()) PrintJson(t);
                    return 0;
                }
                std::printf("%5s %-8s %-15s %-17s %8s %-20s %9s  %s\n", "TASK", "STATE", "KIND",
                            "PIXELS", "ATTEMPTS", "WORKER", "DURATION", "LAST-ERROR");
                for (const pb::TaskInfo& t : resp.tasks()) {
                    const std::string pixels =
                        t.width() > 0
                            ? absl::StrCat(t.x(), ",", t.y(), " ", t.width(), "x", t.height())
                            : "-";
                    const std::string duration =
                        t.leased_unix_ms() > 0 ? absl::StrFormat("%.2f s", t.seconds()) : "-";
                    std::printf("%5d %-8s %-15s %-17s %8d %-20s %9s  %s\n", t.index(),
                                TaskStateName(t.state()).c_str(), TaskKindName(t.kind()).c_str(),
                                pixels.c_str(), t.attempts(),
                                t.worker().empty() ? "-" : LogSafe(t.worker(), 20).c_str(),
                                duration.c_str(), LogSafe(t.last_error(), 200).c_str());
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
                std::unique_ptr<pb::JobService::Stub> stub = Connect(*flags);
                pb::GetTaskLogsRequest req;
                req.set_job_id(*id);
                if (*task >= 0) req.set_task_index(*task);
                Backoff backoff(*flags);
                while (true) {
                    pb::GetTaskLogsResponse resp;
                    const absl::Status s = CallStatus(
                        stub->GetTaskLogs(ContextWithDeadline(absl::Seconds(10)).get(), req, &resp),
                        *flags);
                    if (absl::IsUnavailable(s) && backoff.Wait("logs " + *id, s)) {
                        stub = Connect(*flags);
                        continue;
                    }
                    if (!s.ok()) return ReportError(s);
                    backoff.Reset();
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

}  // namespace lf
