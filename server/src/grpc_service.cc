#include "lf/server/grpc_service.h"

#include <algorithm>
#include <fstream>
#include <functional>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "lf/core/log.h"
#include "lf/job/worker_tags.h"
#include "lf/proto/grpc_status.h"
#include "lf/server/job_dependencies.h"
#include "lf/version.h"
#include "lf/wire/conversions.h"

namespace lf {

namespace pb = lightfarm::v1;

namespace {

constexpr size_t kChunkBytes = 1 << 20;
// How much of an id from the wire an error quotes.
constexpr size_t kIdBytesInErrors = 64;

std::shared_ptr<spdlog::logger> Log() { return NamedLogger("rpc"); }

// Who called, for the log: the peer's address as gRPC reports it.
std::string Peer(const grpc::ServerContext* context) { return LogSafe(context->peer()); }

// The token's name, or "anonymous" with authentication off.
std::string Who(const Caller& caller) {
    return caller.name.empty() ? "anonymous" : absl::StrCat("token ", caller.name);
}

// Streams a file in chunks; stops early when the client goes away. The client hears `what` could
// not be read, never where the file is: paths of the data folder stay in the server's log.
grpc::Status StreamFile(grpc::ServerContext* context, const std::string& path,
                        const std::string& what,
                        const std::function<bool(const pb::Chunk&)>& write) {
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        Log()->error("{}: {} cannot be read", what, path);
        return grpc::Status(grpc::StatusCode::NOT_FOUND, what + " cannot be read on the server");
    }
    // One chunk at a time, read into the message itself: a reader that stalls holds this chunk
    // and what gRPC's flow control lets through, whatever the file's size.
    pb::Chunk chunk;
    std::string& data = *chunk.mutable_data();
    while (in) {
        data.resize(kChunkBytes);
        in.read(data.data(), std::streamsize(data.size()));
        data.resize(size_t(in.gcount()));
        if (data.empty()) break;
        if (context->IsCancelled() || !write(chunk)) {
            return grpc::Status(grpc::StatusCode::CANCELLED, "the client went away");
        }
    }
    return grpc::Status::OK;
}

// The bearer token of the call, as its `authorization` metadata carries it.
std::optional<std::string_view> AuthorizationOf(const grpc::ServerContext* context) {
    const auto& metadata = context->client_metadata();
    auto it = metadata.find("authorization");
    if (it == metadata.end()) return std::nullopt;
    return std::string_view(it->second.data(), it->second.size());
}

// Keeps the task log lines that came with a worker's heartbeat or result: before the message is
// acted on, since its job may end with it. A store that cannot write costs the lines, not the
// result.
// A worker's identity: its token's name before the id it claims, so that one token's workers can
// never name another's leases (lf::PrincipalOf reads the name back). The claimed id alone with
// authentication off.
std::string WorkerIdentity(const Caller& caller, const std::string& claimed) {
    return caller.name.empty() ? claimed : absl::StrCat(caller.name, "/", claimed);
}

template <typename Request>
void TakeTaskLog(Farm& farm, const Request& req, const std::string& worker) {
    if (req.log().empty()) return;
    std::vector<TaskLogLine> lines;
    lines.reserve(size_t(req.log_size()));
    for (const pb::WorkerLogLine& line : req.log()) lines.push_back(FromProto(line));
    if (absl::Status s = farm.TakeTaskLog(req.lease_id(), worker, std::move(lines)); !s.ok()) {
        Log()->error("lease={} worker={}: task log lines lost: {}", LogSafe(req.lease_id()),
                     LogSafe(worker), std::string(s.message()));
    }
}

}  // namespace

absl::StatusOr<Caller> CallGuard::Check(grpc::ServerContext* context, const char* rpc,
                                        Action action) const {
    absl::StatusOr<Caller> caller = auth.Authenticate(AuthorizationOf(context));
    absl::Status s = caller.ok() ? Permit(*caller, action) : caller.status();
    if (s.ok() && action == Action::kWork && worker_certificates &&
        !context->auth_context()->IsPeerAuthenticated()) {
        s = absl::UnauthenticatedError(
            "workers must present a client certificate signed by the server's --tls-client-ca "
            "(lightfarm-worker --tls-cert FILE --tls-key FILE)");
    }
    if (!s.ok()) {
        Log()->warn("{} from {} refused: {}", rpc, Peer(context),
                    LogSafe(std::string(s.message())));
        return s;
    }
    return caller;
}

absl::Status CheckRequestSize(const char* rpc, size_t bytes, size_t max_bytes) {
    if (bytes <= max_bytes) return absl::OkStatus();
    return absl::ResourceExhaustedError(absl::StrCat(rpc, ": a request of ", bytes,
                                                     " bytes is above this call's bound of ",
                                                     max_bytes, " bytes"));
}

JobServiceImpl::JobServiceImpl(Farm& farm, CallGuard guard, JobServiceOptions options)
    : ReadAfterAuth("lightfarm.v1.JobService", guard),
      farm_(farm),
      watchers_({.what = "WatchJob streams",
                 .max = options.max_watchers,
                 .max_flag = "--max-watchers",
                 .max_per_token = options.max_watchers_per_token,
                 .per_token_flag = "--max-watchers-per-token",
                 .hint = "or poll with `lightfarm status`"}),
      // Farm-wide, uploads are bounded by the partial uploads the blob store keeps.
      uploads_({.what = "UploadBlob streams",
                .max_per_token = options.max_uploads_per_token,
                .per_token_flag = "--max-uploads-per-token"}),
      fetches_({.what = "FetchResult streams",
                .max_per_token = options.max_fetches_per_token,
                .per_token_flag = "--max-fetches-per-token"}) {
    using std::bind_front;
    Unary<pb::MissingBlobsRequest, pb::MissingBlobsResponse>(
        "MissingBlobs", Action::kUploadBlobs, kMaxRequestBytes,
        bind_front(&JobServiceImpl::MissingBlobs, this));
    Unary<pb::BlobUploadOffsetRequest, pb::BlobUploadOffsetResponse>(
        "BlobUploadOffset", Action::kUploadBlobs, kMaxRequestBytes,
        bind_front(&JobServiceImpl::BlobUploadOffset, this));
    Unary<pb::SubmitJobRequest, pb::SubmitJobResponse>(
        "SubmitJob", Action::kSubmit, kMaxRequestBytes,
        bind_front(&JobServiceImpl::SubmitJob, this));
    Unary<pb::GetJobRequest, pb::Job>("GetJob", Action::kReadJobs, kMaxRequestBytes,
                                      bind_front(&JobServiceImpl::GetJob, this));
    Unary<pb::ListJobsRequest, pb::ListJobsResponse>("ListJobs", Action::kReadJobs,
                                                     kMaxRequestBytes,
                                                     bind_front(&JobServiceImpl::ListJobs, this));
    ServerStreaming<pb::WatchJobRequest, pb::Job>("WatchJob", Action::kReadJobs,
                                                  bind_front(&JobServiceImpl::WatchJob, this));
    Unary<pb::CancelJobRequest, pb::Job>("CancelJob", Action::kCancelJob, kMaxRequestBytes,
                                         bind_front(&JobServiceImpl::CancelJob, this));
    Unary<pb::SetJobPriorityRequest, pb::Job>("SetJobPriority", Action::kSetPriority,
                                              kMaxRequestBytes,
                                              bind_front(&JobServiceImpl::SetJobPriority, this));
    ServerStreaming<pb::FetchResultRequest, pb::Chunk>(
        "FetchResult", Action::kReadJobs, bind_front(&JobServiceImpl::FetchResult, this));
    Unary<pb::DeleteJobRequest, pb::DeleteJobResponse>(
        "DeleteJob", Action::kDeleteJob, kMaxRequestBytes,
        bind_front(&JobServiceImpl::DeleteJob, this));
    Unary<pb::ListWorkersRequest, pb::ListWorkersResponse>(
        "ListWorkers", Action::kListWorkers, kMaxRequestBytes,
        bind_front(&JobServiceImpl::ListWorkers, this));
    Unary<pb::ListTasksRequest, pb::ListTasksResponse>(
        "ListTasks", Action::kReadJobs, kMaxRequestBytes,
        bind_front(&JobServiceImpl::ListTasks, this));
    Unary<pb::GetTaskLogsRequest, pb::GetTaskLogsResponse>(
        "GetTaskLogs", Action::kReadJobs, kMaxRequestBytes,
        bind_front(&JobServiceImpl::GetTaskLogs, this));
    // Worker management and stats (issue 30)
    Unary<pb::SetWorkerStateRequest, pb::SetWorkerStateResponse>(
        "SetWorkerState", Action::kManageWorkers, kMaxRequestBytes,
        bind_front(&JobServiceImpl::SetWorkerState, this));
    // Job management (issue 30).
    Unary<pb::RequeueJobRequest, pb::Job>("RequeueJob", Action::kManageJobs, kMaxRequestBytes,
                                          bind_front(&JobServiceImpl::RequeueJob, this));
    Unary<pb::PauseJobRequest, pb::Job>("PauseJob", Action::kManageJobs, kMaxRequestBytes,
                                        bind_front(&JobServiceImpl::PauseJob, this));
    Unary<pb::ResumeJobRequest, pb::Job>("ResumeJob", Action::kManageJobs, kMaxRequestBytes,
                                         bind_front(&JobServiceImpl::ResumeJob, this));
    // History (issue 30): read as jobs are, everyone's for an admin, a submitter's own.
    Unary<pb::GetStatsRequest, pb::GetStatsResponse>("GetStats", Action::kReadJobs,
                                                     kMaxRequestBytes,
                                                     bind_front(&JobServiceImpl::GetStats, this));
    // Dependencies (issue 30).
    Unary<pb::AddJobDependenciesRequest, pb::Job>(
        "AddJobDependencies", Action::kManageJobs, kMaxRequestBytes,
        bind_front(&JobServiceImpl::AddJobDependencies, this));
}

WorkerServiceImpl::WorkerServiceImpl(Farm& farm, CallGuard guard)
    : ReadAfterAuth("lightfarm.v1.WorkerService", guard), farm_(farm) {
    using std::bind_front;
    Unary<pb::LeaseTaskRequest, pb::LeaseTaskResponse>(
        "LeaseTask", Action::kWork, kMaxRequestBytes,
        bind_front(&WorkerServiceImpl::LeaseTask, this));
    Unary<pb::HeartbeatRequest, pb::HeartbeatResponse>(
        "Heartbeat", Action::kWork, kMaxRequestBytes,
        bind_front(&WorkerServiceImpl::Heartbeat, this));
    // The one large message: a task's result, from a worker whose token was checked first.
    Unary<pb::CompleteTaskRequest, pb::CompleteTaskResponse>(
        "CompleteTask", Action::kWork, size_t(kMaxTaskResultBytes),
        bind_front(&WorkerServiceImpl::CompleteTask, this));
    Unary<pb::FailTaskRequest, pb::FailTaskResponse>(
        "FailTask", Action::kWork, kMaxRequestBytes,
        bind_front(&WorkerServiceImpl::FailTask, this));
    ServerStreaming<pb::FetchBlobRequest, pb::Chunk>(
        "FetchBlob", Action::kWork, bind_front(&WorkerServiceImpl::FetchBlob, this));
}

absl::StatusOr<JobRecord> JobServiceImpl::VisibleJob(const Caller& caller,
                                                     const std::string& job_id) const {
    // Job ids are "job-" and 10 hex digits: a longer one is nobody's, and is not echoed back
    // (a megabyte-long id came back whole in GetJob's error).
    if (job_id.size() > kIdBytesInErrors) {
        return absl::NotFoundError(absl::StrCat("no job ", LogSafe(job_id, kIdBytesInErrors), " (",
                                                job_id.size(), " bytes)"));
    }
    absl::StatusOr<JobRecord> job = farm_.scheduler().Get(job_id);
    if (job.ok() && !MaySee(caller, job->spec.owner))
        return absl::NotFoundError("no job " + LogSafe(job_id, kIdBytesInErrors));
    return job;
}

grpc::Status JobServiceImpl::MissingBlobs(grpc::ServerContext* context, const Caller& caller,
                                          const pb::MissingBlobsRequest& req,
                                          pb::MissingBlobsResponse* resp) {
    for (const std::string& hash : req.hashes()) {
        // Touched: the client will not upload it, and may submit a job naming it.
        if (!farm_.blobs().Touch(hash)) resp->add_hashes(hash);
    }
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::BlobUploadOffset(grpc::ServerContext* context, const Caller& caller,
                                              const pb::BlobUploadOffsetRequest& req,
                                              pb::BlobUploadOffsetResponse* resp) {
    absl::StatusOr<uint64_t> offset = farm_.blobs().UploadOffset(req.hash(), req.size());
    if (!offset.ok()) return ToGrpcStatus(offset.status());
    resp->set_offset(*offset);
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::UploadBlob(grpc::ServerContext* context,
                                        grpc::ServerReader<pb::UploadBlobRequest>* reader,
                                        pb::UploadBlobResponse*) {
    absl::StatusOr<Caller> caller = guard_.Check(context, "UploadBlob", Action::kUploadBlobs);
    if (!caller.ok()) return ToGrpcStatus(caller.status());
    absl::StatusOr<StreamSlots::Slot> slot = uploads_.Take(caller->name);
    if (!slot.ok()) {
        Log()->warn("upload from {} refused: {}", Peer(context),
                    std::string(slot.status().message()));
        return ToGrpcStatus(slot.status());
    }
    pb::UploadBlobRequest chunk;
    if (!reader->Read(&chunk)) {
        return ToGrpcStatus(absl::InvalidArgumentError("UploadBlob: empty stream"));
    }
    const std::string hash = LogSafe(chunk.hash());
    absl::StatusOr<std::unique_ptr<BlobStore::Upload>> upload =
        farm_.StartUpload(chunk.hash(), chunk.size(), chunk.offset());
    // Another stream stored it meanwhile: what this one brings is not needed.
    if (absl::IsAlreadyExists(upload.status())) return grpc::Status::OK;
    if (!upload.ok()) {
        Log()->warn("blob {}: upload from {} refused: {}", hash, Peer(context),
                    LogSafe(std::string(upload.status().message())));
        return ToGrpcStatus(upload.status());
    }
    BlobStore::Upload& up = **upload;
    if (up.offset() > 0) {
        Log()->info("blob {}: upload from {} resumes at byte {} of {}", hash, Peer(context),
                    up.offset(), chunk.size());
    }
    absl::Status s;
    do {
        s = up.Append(chunk.data());
    } while (s.ok() && reader->Read(&chunk));
    if (s.ok()) s = up.Finish();
    if (s.ok()) {
        Log()->info("blob {}: stored, {} bytes, {} of them received from {} in this upload", hash,
                    up.offset() + up.received(), up.received(), Peer(context));
    } else {
        Log()->warn("blob {}: upload from {} ended after {} bytes received (from byte {}): {}",
                    hash, Peer(context), up.received(), up.offset(),
                    LogSafe(std::string(s.message())));
    }
    return ToGrpcStatus(s);
}

grpc::Status JobServiceImpl::SubmitJob(grpc::ServerContext* context, const Caller& caller,
                                       const pb::SubmitJobRequest& req,
                                       pb::SubmitJobResponse* resp) {
    // Proto3 keeps enum values this build does not know; JobSpec cannot hold them, so they are
    // refused here rather than rendered as something the client did not ask for.
    if (!pb::PixelFilterType_IsValid(req.params().filter_type())) {
        return ToGrpcStatus(absl::InvalidArgumentError(
            absl::StrCat("params.filter_type ", req.params().filter_type(),
                         ": unknown pixel filter; expected box, gaussian or blackman-harris")));
    }
    if (!pb::SamplerType_IsValid(req.params().sampler())) {
        return ToGrpcStatus(absl::InvalidArgumentError(
            absl::StrCat("params.sampler ", req.params().sampler(),
                         ": unknown sampler; expected independent or sobol")));
    }
    if (!pb::LightStrategy_IsValid(req.params().light_strategy())) {
        return ToGrpcStatus(absl::InvalidArgumentError(
            absl::StrCat("params.light_strategy ", req.params().light_strategy(),
                         ": unknown light sampling strategy; expected power or bvh")));
    }
    JobSpec spec = FromProto(req);
    spec.owner = caller.name;
    if (absl::Status s = CheckVisibleDependencies(caller, spec.after); !s.ok()) {
        return ToGrpcStatus(s);
    }
    absl::StatusOr<std::string> id = farm_.Submit(std::move(spec));
    if (!id.ok()) {
        Log()->warn("submission of \"{}\" from {} refused: {}", LogSafe(req.name()), Peer(context),
                    LogSafe(std::string(id.status().message())));
        return ToGrpcStatus(id.status());
    }
    Log()->info("job={} submitted by {} from {}: \"{}\"", *id, Who(caller), Peer(context),
                LogSafe(req.name()));
    resp->set_job_id(*id);
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::GetJob(grpc::ServerContext* context, const Caller& caller,
                                    const pb::GetJobRequest& req, pb::Job* resp) {
    absl::StatusOr<JobRecord> job = VisibleJob(caller, req.job_id());
    if (!job.ok()) return ToGrpcStatus(job.status());
    ToProto(*job, resp);
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::ListJobs(grpc::ServerContext* context, const Caller& caller,
                                      const pb::ListJobsRequest& req, pb::ListJobsResponse* resp) {
    if (req.page_size() < 0) {
        return ToGrpcStatus(absl::InvalidArgumentError(
            absl::StrCat("ListJobs: page_size ", req.page_size(), " is negative")));
    }
    const int page_size =
        req.page_size() == 0 ? kDefaultPageSize : std::min(req.page_size(), kMaxPageSize);
    // The token is the seq of the page's last job: the next page starts below it.
    JobQuery query{.limit = size_t(page_size) + 1};
    if (caller.role != Role::kAdmin) query.owner = caller.name;
    if (!req.page_token().empty() &&
        (!absl::SimpleAtoi(req.page_token(), &query.before_seq) || query.before_seq == 0)) {
        return ToGrpcStatus(
            absl::InvalidArgumentError("ListJobs: page_token is not one this server gave out"));
    }
    absl::StatusOr<std::vector<JobRecord>> jobs = farm_.scheduler().List(query);
    if (!jobs.ok()) return ToGrpcStatus(jobs.status());
    if (jobs->size() > size_t(page_size)) {
        jobs->resize(size_t(page_size));
        resp->set_next_page_token(absl::StrCat(jobs->back().seq));
    }
    for (const JobRecord& job : *jobs) {
        pb::Job* listed = resp->add_jobs();
        ToProto(job, listed);
        // A list shows frames done/total; each frame's progress is GetJob's (a page of long
        // shots would pass a client's 4 MiB message limit).
        listed->clear_frames();
    }
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::WatchJob(grpc::ServerContext* context, const Caller& caller,
                                      const pb::WatchJobRequest& req,
                                      const std::function<bool(const pb::Job&)>& write) {
    // Checked once: a job's owner never changes.
    if (absl::StatusOr<JobRecord> job = VisibleJob(caller, req.job_id()); !job.ok()) {
        return ToGrpcStatus(job.status());
    }
    // Each stream holds a server thread until its job ends: bounded, so that watchers cannot
    // take every thread (or the memory of thousands).
    absl::StatusOr<StreamSlots::Slot> slot = watchers_.Take(caller.name);
    if (!slot.ok()) {
        Log()->warn("watch of job={} from {} refused: {}", LogSafe(req.job_id()), Peer(context),
                    std::string(slot.status().message()));
        return ToGrpcStatus(slot.status());
    }
    // At most five messages a second but for the job's end, and one at least every few seconds
    // so a dead client is noticed.
    constexpr absl::Duration kMinGap = absl::Milliseconds(200), kMaxGap = absl::Seconds(5);
    using EndWait = Scheduler::EndWait;
    Scheduler& scheduler = farm_.scheduler();
    std::string last_sent;
    absl::Time last_time = absl::InfinitePast();
    // Taken before each read, so a change during the read or the pause is never missed.
    uint64_t version = scheduler.WaitForChange(0, absl::InfinitePast());
    while (!context->IsCancelled()) {
        // A job's end is read once it settled: a client acting on it at once (a `requeue`, a
        // `list`) finds the job's record in the store.
        absl::StatusOr<std::optional<JobRecord>> job = scheduler.GetSettled(req.job_id());
        if (!job.ok()) return ToGrpcStatus(job.status());
        if (*job) {
            pb::Job message;
            ToProto(**job, &message);
            std::string bytes = message.SerializeAsString();
            if (bytes != last_sent || absl::Now() - last_time > kMaxGap) {
                // A token revoked meanwhile ends the stream (within the Authenticator's cache
                // time).
                if (auto c = guard_.Check(context, "WatchJob", Action::kReadJobs); !c.ok()) {
                    return ToGrpcStatus(c.status());
                }
                if (!write(message)) break;
                last_sent = std::move(bytes);
                last_time = absl::Now();
            }
            if (IsFinal((*job)->state)) break;
        }
        // The gap ends early when the job's end settles: that goes out at once.
        const EndWait paced = scheduler.WaitForEnd(req.job_id(), absl::Now() + kMinGap);
        if (paced == EndWait::kShutdown) {
            return grpc::Status(grpc::StatusCode::UNAVAILABLE, "the server is shutting down");
        }
        if (paced == EndWait::kRunning) {
            version = scheduler.WaitForChange(version, absl::Now() + absl::Seconds(1));
        }
    }
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::CancelJob(grpc::ServerContext* context, const Caller& caller,
                                       const pb::CancelJobRequest& req, pb::Job* resp) {
    if (absl::StatusOr<JobRecord> seen = VisibleJob(caller, req.job_id()); !seen.ok()) {
        return ToGrpcStatus(seen.status());
    }
    absl::StatusOr<JobRecord> job = farm_.scheduler().Cancel(req.job_id());
    if (!job.ok()) return ToGrpcStatus(job.status());
    Log()->info("job={} cancelled by {} from {}", job->id, Who(caller), Peer(context));
    ToProto(*job, resp);
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::SetJobPriority(grpc::ServerContext* context, const Caller& caller,
                                            const pb::SetJobPriorityRequest& req, pb::Job* resp) {
    if (absl::StatusOr<JobRecord> seen = VisibleJob(caller, req.job_id()); !seen.ok()) {
        return ToGrpcStatus(seen.status());
    }
    absl::StatusOr<JobRecord> job = farm_.SetPriority(req.job_id(), req.priority());
    if (!job.ok()) return ToGrpcStatus(job.status());
    Log()->info("job={} priority set to {} by {} from {}", job->id, req.priority(), Who(caller),
                Peer(context));
    ToProto(*job, resp);
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::RequeueJob(grpc::ServerContext* context, const Caller& caller,
                                        const pb::RequeueJobRequest& req, pb::Job* resp) {
    if (absl::StatusOr<JobRecord> seen = VisibleJob(caller, req.job_id()); !seen.ok()) {
        return ToGrpcStatus(seen.status());
    }
    std::optional<FrameRange> frames;
    if (!req.frames().empty()) {
        // Echoed in the error: bounded first ("-1000000--1000000:1000000" is the longest range).
        constexpr size_t kMaxRangeText = 64;
        absl::StatusOr<FrameRange> range =
            req.frames().size() > kMaxRangeText
                ? absl::InvalidArgumentError(
                      absl::StrCat(req.frames().size(), " bytes, not a range A-B[:STEP]"))
                : ParseFrameRange(req.frames());
        if (!range.ok()) {
            return ToGrpcStatus(
                absl::InvalidArgumentError(absl::StrCat("frames: ", range.status().message())));
        }
        frames = *range;
    }
    absl::StatusOr<JobRecord> job = farm_.Requeue(req.job_id(), frames);
    if (!job.ok()) return ToGrpcStatus(job.status());
    Log()->info("job={} requeued{} by {} from {}", job->id,
                frames ? " (frames " + FrameRangeText(*frames) + ")" : "", Who(caller),
                Peer(context));
    ToProto(*job, resp);
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::GetStats(grpc::ServerContext* context, const Caller& caller,
                                      const pb::GetStatsRequest& req, pb::GetStatsResponse* resp) {
    StatsQuery query;
    if (req.since_unix_ms() != 0) {
        query.since = absl::FromUnixMillis(req.since_unix_ms());
        // A minute's leeway: the client's clock, which made `since`, may run a little ahead.
        if (query.since > absl::Now() + absl::Minutes(1)) {
            return ToGrpcStatus(absl::InvalidArgumentError(absl::StrCat(
                "GetStats: since ", absl::FormatTime(query.since), " is in the future")));
        }
    }
    if (!req.owner().empty()) query.owner = req.owner();
    if (!MaySee(caller, req.owner().empty() ? caller.name : req.owner())) {
        return ToGrpcStatus(absl::PermissionDeniedError(
            absl::StrCat("token \"", caller.name, "\" may see only its own jobs' stats, not ",
                         LogSafe(req.owner(), kIdBytesInErrors), "'s")));
    }
    // A submitter's own jobs only, and the workers' rows of their tasks only.
    if (caller.role != Role::kAdmin) query.owner = caller.name;
    absl::StatusOr<FarmStats> stats = farm_.store().Stats(query);
    if (!stats.ok()) return ToGrpcStatus(stats.status());
    ToProto(*stats, resp);
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::AddJobDependencies(grpc::ServerContext* context, const Caller& caller,
                                                const pb::AddJobDependenciesRequest& req,
                                                pb::Job* resp) {
    if (absl::StatusOr<JobRecord> seen = VisibleJob(caller, req.job_id()); !seen.ok()) {
        return ToGrpcStatus(seen.status());
    }
    const std::vector<std::string> after(req.after().begin(), req.after().end());
    if (absl::Status s = CheckVisibleDependencies(caller, after); !s.ok()) return ToGrpcStatus(s);
    absl::StatusOr<JobRecord> job = farm_.scheduler().AddDependencies(req.job_id(), after);
    if (!job.ok()) return ToGrpcStatus(job.status());
    Log()->info("job={} runs after {} by {} from {}", job->id, absl::StrJoin(job->spec.after, ","),
                Who(caller), Peer(context));
    ToProto(*job, resp);
    return grpc::Status::OK;
}

absl::Status JobServiceImpl::CheckVisibleDependencies(const Caller& caller,
                                                      const std::vector<std::string>& after) const {
    absl::StatusOr<std::vector<std::string>> ids = CheckDependencyIds(after, "after");
    if (!ids.ok()) return ids.status();
    for (const std::string& id : *ids) {
        // Another owner's job is as unknown to the caller as one never submitted.
        if (absl::StatusOr<JobRecord> job = VisibleJob(caller, id); !job.ok()) {
            return absl::Status(job.status().code(),
                                absl::StrCat("dependency ", id, ": ", job.status().message()));
        }
    }
    return absl::OkStatus();
}

grpc::Status JobServiceImpl::PauseJob(grpc::ServerContext* context, const Caller& caller,
                                      const pb::PauseJobRequest& req, pb::Job* resp) {
    return SetPaused(context, caller, req.job_id(), true, resp);
}

grpc::Status JobServiceImpl::ResumeJob(grpc::ServerContext* context, const Caller& caller,
                                       const pb::ResumeJobRequest& req, pb::Job* resp) {
    return SetPaused(context, caller, req.job_id(), false, resp);
}

grpc::Status JobServiceImpl::SetPaused(grpc::ServerContext* context, const Caller& caller,
                                       const std::string& job_id, bool paused, pb::Job* resp) {
    if (absl::StatusOr<JobRecord> seen = VisibleJob(caller, job_id); !seen.ok()) {
        return ToGrpcStatus(seen.status());
    }
    absl::StatusOr<JobRecord> job = farm_.scheduler().SetPaused(job_id, paused);
    if (!job.ok()) return ToGrpcStatus(job.status());
    Log()->info("job={} {} by {} from {}", job->id, paused ? "paused" : "resumed", Who(caller),
                Peer(context));
    ToProto(*job, resp);
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::FetchResult(grpc::ServerContext* context, const Caller& caller,
                                         const pb::FetchResultRequest& req,
                                         const std::function<bool(const pb::Chunk&)>& write) {
    if (absl::StatusOr<JobRecord> job = VisibleJob(caller, req.job_id()); !job.ok()) {
        return ToGrpcStatus(job.status());
    }
    absl::StatusOr<std::string> path =
        farm_.ResultFile(req.job_id(), req.preview(),
                         req.has_frame() ? std::optional<int>(req.frame()) : std::nullopt);
    if (!path.ok()) return ToGrpcStatus(path.status());
    absl::StatusOr<StreamSlots::Slot> slot = fetches_.Take(caller.name);
    if (!slot.ok()) {
        Log()->warn("fetch of job={} from {} refused: {}", LogSafe(req.job_id()), Peer(context),
                    std::string(slot.status().message()));
        return ToGrpcStatus(slot.status());
    }
    return StreamFile(context, *path, "the result of job " + req.job_id(), write);
}

grpc::Status JobServiceImpl::DeleteJob(grpc::ServerContext* context, const Caller& caller,
                                       const pb::DeleteJobRequest& req, pb::DeleteJobResponse*) {
    if (absl::StatusOr<JobRecord> job = VisibleJob(caller, req.job_id()); !job.ok()) {
        return ToGrpcStatus(job.status());
    }
    if (absl::Status s = farm_.DeleteJob(req.job_id()); !s.ok()) return ToGrpcStatus(s);
    Log()->info("job={} deleted by {} from {}", LogSafe(req.job_id()), Who(caller), Peer(context));
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::ListWorkers(grpc::ServerContext* context, const Caller& caller,
                                         const pb::ListWorkersRequest& req,
                                         pb::ListWorkersResponse* resp) {
    for (WorkerStatus& worker : farm_.scheduler().Workers()) {
        // A submitter sees that a worker is busy, not with whose job.
        if (worker.busy() && !VisibleJob(caller, worker.job_id).ok()) worker.job_id = "(other)";
        ToProto(worker, resp->add_workers());
    }
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::SetWorkerState(grpc::ServerContext* context, const Caller& caller,
                                            const pb::SetWorkerStateRequest& req,
                                            pb::SetWorkerStateResponse* resp) {
    WorkerControl control;
    switch (req.control()) {
        case pb::SetWorkerStateRequest::ENABLE:
            control = WorkerControl::kEnabled;
            break;
        case pb::SetWorkerStateRequest::DISABLE:
            control = WorkerControl::kDisabled;
            break;
        case pb::SetWorkerStateRequest::DRAIN:
            control = WorkerControl::kDrain;
            break;
        default:
            return ToGrpcStatus(absl::InvalidArgumentError(
                absl::StrCat("SetWorkerState of ", LogSafe(req.worker(), 128), ": control ",
                             int(req.control()), " is none of enable, disable, drain")));
    }
    absl::StatusOr<std::vector<WorkerStatus>> workers = farm_.SetWorkerState(req.worker(), control);
    if (!workers.ok()) return ToGrpcStatus(workers.status());
    Log()->info("worker {} set to {} by {} from {}", LogSafe(req.worker(), 128),
                WorkerControlName(control), Who(caller), Peer(context));
    for (const WorkerStatus& worker : *workers) ToProto(worker, resp->add_workers());
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::ListTasks(grpc::ServerContext* context, const Caller& caller,
                                       const pb::ListTasksRequest& req,
                                       pb::ListTasksResponse* resp) {
    if (absl::StatusOr<JobRecord> job = VisibleJob(caller, req.job_id()); !job.ok()) {
        return ToGrpcStatus(job.status());
    }
    absl::StatusOr<std::vector<TaskStatus>> tasks = farm_.Tasks(req.job_id());
    if (!tasks.ok()) return ToGrpcStatus(tasks.status());
    for (const TaskStatus& task : *tasks) ToProto(task, resp->add_tasks());
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::GetTaskLogs(grpc::ServerContext* context, const Caller& caller,
                                         const pb::GetTaskLogsRequest& req,
                                         pb::GetTaskLogsResponse* resp) {
    if (absl::StatusOr<JobRecord> job = VisibleJob(caller, req.job_id()); !job.ok()) {
        return ToGrpcStatus(job.status());
    }
    absl::StatusOr<TaskLogPage> page = farm_.TaskLogs(
        req.job_id(), req.has_task_index() ? std::optional<int>(req.task_index()) : std::nullopt,
        req.after_seq(), req.max_lines());
    if (!page.ok()) return ToGrpcStatus(page.status());
    for (const TaskLogLine& line : page->lines) ToProto(line, resp->add_lines());
    resp->set_next_seq(page->next_seq);
    resp->set_job_ended(page->job_ended);
    return grpc::Status::OK;
}

grpc::Status WorkerServiceImpl::LeaseTask(grpc::ServerContext* context, const Caller& caller,
                                          const pb::LeaseTaskRequest& req,
                                          pb::LeaseTaskResponse* resp) {
    if (req.worker_id().empty()) {
        return ToGrpcStatus(absl::InvalidArgumentError("LeaseTask: worker_id is empty"));
    }
    if (req.version() != kBuildVersion) {
        return ToGrpcStatus(absl::FailedPreconditionError(absl::StrCat(
            "worker version ", req.version().empty() ? "(none)" : req.version(),
            ", server version ", kBuildVersion, ": run workers of the server's build")));
    }
    if (req.name().size() > kMaxWorkerNameBytes) {
        return ToGrpcStatus(absl::InvalidArgumentError(
            absl::StrCat("LeaseTask: worker name of ", req.name().size(),
                         " bytes is above the limit of ", kMaxWorkerNameBytes)));
    }
    const std::vector<std::string> tags(req.tags().begin(), req.tags().end());
    if (absl::Status s = CheckTags(tags, "LeaseTask: worker tags"); !s.ok()) {
        return ToGrpcStatus(absl::InvalidArgumentError(absl::StrCat(
            LogSafe(std::string(s.message())), " (worker ", LogSafe(req.worker_id()), ")")));
    }
    const WorkerDescription about{req.name(), context->peer(), req.version(), tags};
    const absl::Duration wait = absl::Milliseconds(std::clamp(req.wait_ms(), 0, 10000));
    if (std::optional<TaskAssignment> lease = farm_.scheduler().LeaseTask(
            WorkerIdentity(caller, req.worker_id()), absl::Now() + wait, &about)) {
        ToProto(*lease, resp->mutable_task());
    }
    return grpc::Status::OK;
}

grpc::Status WorkerServiceImpl::Heartbeat(grpc::ServerContext* context, const Caller& caller,
                                          const pb::HeartbeatRequest& req,
                                          pb::HeartbeatResponse* resp) {
    const std::string worker = WorkerIdentity(caller, req.worker_id());
    TakeTaskLog(farm_, req, worker);
    resp->set_cancelled(!farm_.scheduler().Heartbeat(req.lease_id(), worker));
    return grpc::Status::OK;
}

grpc::Status WorkerServiceImpl::CompleteTask(grpc::ServerContext* context, const Caller& caller,
                                             const pb::CompleteTaskRequest& req,
                                             pb::CompleteTaskResponse*) {
    const std::string worker = WorkerIdentity(caller, req.worker_id());
    TakeTaskLog(farm_, req, worker);
    std::vector<Farm::ResultPart> parts;
    for (const pb::TaskPartResult& part : req.parts()) {
        parts.push_back(
            {part.frame(), part.tile_sums(),
             part.splats().empty() ? std::nullopt : std::optional<std::string_view>(part.splats()),
             ReportedTimes(part.render_seconds(), part.cpu_seconds())});
    }
    // As the worker measured them: shown and summed, never trusted for anything else.
    const TaskTimes times = ReportedTimes(req.seconds(), req.cpu_seconds());
    const absl::Status s =
        req.radiosity_sweep().empty()
            ? farm_.Complete(
                  req.lease_id(), worker, req.tile_sums(),
                  req.has_radiosity() ? std::optional<RadiosityFigures>(FromProto(req.radiosity()))
                                      : std::nullopt,
                  // An encoded list is never empty: empty means a tile's result.
                  req.splats().empty() ? std::nullopt
                                       : std::optional<std::string_view>(req.splats()),
                  req.has_frame() ? std::optional<int>(req.frame()) : std::nullopt, parts, times)
            : farm_.CompleteSweep(req.lease_id(), worker, req.radiosity_sweep(), times,
                                  req.has_radiosity()
                                      ? std::optional<RadiosityFigures>(FromProto(req.radiosity()))
                                      : std::nullopt);
    if (!s.ok()) {
        Log()->warn("{}", RefusedResultLine(req.lease_id(), worker, context->peer(),
                                            std::string(s.message())));
    }
    return ToGrpcStatus(s);
}

std::string RefusedResultLine(std::string_view lease_id, std::string_view worker_id,
                              std::string_view peer, std::string_view why) {
    // Every part came from the wire: the ids and the peer, and the reason, which quotes them.
    return absl::StrCat("lease=", LogSafe(lease_id), " worker=", LogSafe(worker_id), " from ",
                        LogSafe(peer), ": CompleteTask refused: ", LogSafe(why, 1024));
}

grpc::Status WorkerServiceImpl::FailTask(grpc::ServerContext* context, const Caller& caller,
                                         const pb::FailTaskRequest& req, pb::FailTaskResponse*) {
    const std::string worker = WorkerIdentity(caller, req.worker_id());
    TakeTaskLog(farm_, req, worker);
    const FailureKind kind = req.kind() == pb::FailTaskRequest::WORKER_SHUTDOWN
                                 ? FailureKind::kWorkerShutdown
                                 : FailureKind::kTaskError;
    // Kept with the task, the job's last error and the blocklist, all saved with every record
    // write and printed by the CLI: one bounded line, its control characters escaped.
    return ToGrpcStatus(
        farm_.scheduler().Fail(req.lease_id(), worker, LogSafe(req.reason(), 1024), kind));
}

grpc::Status WorkerServiceImpl::FetchBlob(grpc::ServerContext* context, const Caller& caller,
                                          const pb::FetchBlobRequest& req,
                                          const std::function<bool(const pb::Chunk&)>& write) {
    if (!farm_.blobs().Has(req.hash())) {
        return ToGrpcStatus(
            absl::NotFoundError("no blob " + LogSafe(req.hash(), kIdBytesInErrors)));
    }
    return StreamFile(context, farm_.blobs().PathOf(req.hash()), "blob " + req.hash(), write);
}

}  // namespace lf
