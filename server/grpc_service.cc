#include "server/grpc_service.h"

#include <algorithm>
#include <fstream>

#include "absl/strings/str_cat.h"
#include "lf/core/log.h"
#include "proto/grpc_status.h"
#include "proto/radiosity_params.h"

namespace lf {

namespace pb = lightfarm::v1;

namespace {

constexpr size_t kChunkBytes = 1 << 20;

std::shared_ptr<spdlog::logger> Log() { return NamedLogger("rpc"); }

int64_t UnixMillis(absl::Time t) { return t == absl::InfinitePast() ? 0 : absl::ToUnixMillis(t); }

pb::Job::State ToProto(JobState s) {
    switch (s) {
        case JobState::kQueued:
            return pb::Job::QUEUED;
        case JobState::kRunning:
            return pb::Job::RUNNING;
        case JobState::kSucceeded:
            return pb::Job::SUCCEEDED;
        case JobState::kFailed:
            return pb::Job::FAILED;
        case JobState::kCancelled:
            return pb::Job::CANCELLED;
    }
    return pb::Job::STATE_UNSPECIFIED;
}

void ToProto(const BlobRef& ref, pb::SceneFile* out) {
    out->set_path(ref.path);
    out->set_hash(ref.hash);
    out->set_size(ref.size);
}

BlobRef FromProto(const pb::SceneFile& f) { return {f.path(), f.hash(), f.size()}; }

void ToProto(const JobSpec& spec, pb::RenderParams* out) {
    out->set_spp(spec.plan.spp);
    out->set_seed(spec.seed);
    out->set_max_depth(spec.max_depth);
    out->set_tile(spec.plan.tile);
    out->set_passes(spec.plan.passes);
    out->set_method(spec.method);
    if (spec.method == "radiosity") lf::ToProto(spec.radiosity, out->mutable_radiosity());
    out->set_target_error(spec.adaptive.target_error);
    out->set_time_limit_seconds(spec.adaptive.time_limit);
    out->set_max_spp(spec.adaptive.max_spp);
}

void ToProto(const JobRecord& job, pb::Job* out) {
    out->set_id(job.id);
    out->set_name(job.spec.name);
    out->set_state(ToProto(job.state));
    out->set_error(job.error);
    ToProto(job.spec, out->mutable_params());
    out->set_priority(job.spec.priority);
    out->set_width(job.spec.plan.width);
    out->set_height(job.spec.plan.height);
    out->set_scene_hash(job.spec.scene_hash);
    out->set_tasks_total(job.tasks_total);
    out->set_tasks_done(job.tasks_done);
    out->set_tasks_running(job.tasks_running);
    out->set_samples(job.stats.samples);
    out->set_rays(job.stats.rays);
    out->set_invalid_samples(job.stats.invalid_samples);
    out->set_submitted_unix_ms(UnixMillis(job.submitted));
    out->set_started_unix_ms(UnixMillis(job.started));
    out->set_finished_unix_ms(UnixMillis(job.finished));
    out->set_retries(job.retries);
    out->set_tasks_leased(job.tasks_leased);
}

JobSpec FromProto(const pb::SubmitJobRequest& r) {
    JobSpec spec;
    spec.name = r.name().empty() ? r.scene().path() : r.name();
    spec.request_id = r.request_id();
    spec.scene = FromProto(r.scene());
    for (const pb::SceneFile& f : r.files()) spec.files.push_back(FromProto(f));
    spec.plan.spp = r.params().spp();
    spec.plan.tile = r.params().tile();
    spec.plan.passes = r.params().passes();
    spec.seed = r.params().seed();
    spec.max_depth = r.params().max_depth();
    if (!r.params().method().empty()) spec.method = r.params().method();
    if (r.params().has_radiosity()) spec.radiosity = lf::FromProto(r.params().radiosity());
    spec.adaptive.target_error = r.params().target_error();
    spec.adaptive.time_limit = r.params().time_limit_seconds();
    if (r.params().max_spp() != 0) spec.adaptive.max_spp = r.params().max_spp();
    spec.priority = r.priority();
    return spec;
}

void ToProto(const Lease& lease, const FarmOptions& options, pb::Task* out) {
    out->set_lease_id(lease.id);
    out->set_job_id(lease.job_id);
    out->set_task_index(lease.task.index);
    ToProto(lease.spec.scene, out->mutable_scene());
    for (const BlobRef& f : lease.spec.files) ToProto(f, out->add_files());
    ToProto(lease.spec, out->mutable_params());
    out->set_x0(lease.task.rect.x0);
    out->set_y0(lease.task.rect.y0);
    out->set_width(lease.task.rect.width);
    out->set_height(lease.task.rect.height);
    out->set_sample_begin(lease.task.sample_begin);
    out->set_sample_end(lease.task.sample_end);
    if (lease.sweep >= 0) {
        out->set_kind(pb::Task::RADIOSITY_SWEEP);
        out->set_sweep(lease.sweep);
        out->set_chunk(lease.chunk);
    }
    out->set_radiosity_hash(lease.radiosity_hash);
    out->set_heartbeat_interval_ms(int(absl::ToInt64Milliseconds(options.heartbeat_interval)));
    out->set_lease_ms(int(absl::ToInt64Milliseconds(options.scheduler.lease)));
}

// Streams a file in chunks; stops early when the client goes away.
grpc::Status StreamFile(grpc::ServerContext* context, const std::string& path,
                        grpc::ServerWriter<pb::Chunk>* writer) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return grpc::Status(grpc::StatusCode::NOT_FOUND, path + ": cannot be read");
    std::string buffer(kChunkBytes, '\0');
    pb::Chunk chunk;
    while (in) {
        in.read(buffer.data(), std::streamsize(buffer.size()));
        if (in.gcount() == 0) break;
        chunk.set_data(buffer.data(), size_t(in.gcount()));
        if (context->IsCancelled() || !writer->Write(chunk)) {
            return grpc::Status(grpc::StatusCode::CANCELLED, "the client went away");
        }
    }
    return grpc::Status::OK;
}

}  // namespace

grpc::Status JobServiceImpl::MissingBlobs(grpc::ServerContext*, const pb::MissingBlobsRequest* req,
                                          pb::MissingBlobsResponse* resp) {
    for (const std::string& hash : req->hashes()) {
        if (!farm_.blobs().Has(hash)) resp->add_hashes(hash);
    }
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::UploadBlob(grpc::ServerContext*,
                                        grpc::ServerReader<pb::UploadBlobRequest>* reader,
                                        pb::UploadBlobResponse*) {
    pb::UploadBlobRequest chunk;
    if (!reader->Read(&chunk)) {
        return ToGrpcStatus(absl::InvalidArgumentError("UploadBlob: empty stream"));
    }
    absl::StatusOr<std::unique_ptr<BlobStore::Upload>> upload =
        farm_.StartUpload(chunk.hash(), chunk.size());
    if (!upload.ok()) return ToGrpcStatus(upload.status());
    do {
        if (absl::Status s = (*upload)->Append(chunk.data()); !s.ok()) return ToGrpcStatus(s);
    } while (reader->Read(&chunk));
    return ToGrpcStatus((*upload)->Finish());
}

grpc::Status JobServiceImpl::SubmitJob(grpc::ServerContext*, const pb::SubmitJobRequest* req,
                                       pb::SubmitJobResponse* resp) {
    absl::StatusOr<std::string> id = farm_.Submit(FromProto(*req));
    if (!id.ok()) return ToGrpcStatus(id.status());
    resp->set_job_id(*id);
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::GetJob(grpc::ServerContext*, const pb::GetJobRequest* req,
                                    pb::Job* resp) {
    absl::StatusOr<JobRecord> job = farm_.scheduler().Get(req->job_id());
    if (!job.ok()) return ToGrpcStatus(job.status());
    ToProto(*job, resp);
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::ListJobs(grpc::ServerContext*, const pb::ListJobsRequest*,
                                      pb::ListJobsResponse* resp) {
    for (const JobRecord& job : farm_.scheduler().List()) ToProto(job, resp->add_jobs());
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::WatchJob(grpc::ServerContext* context, const pb::WatchJobRequest* req,
                                      grpc::ServerWriter<pb::Job>* writer) {
    // At most five messages a second, and one at least every few seconds so a dead client is
    // noticed.
    constexpr absl::Duration kMinGap = absl::Milliseconds(200), kMaxGap = absl::Seconds(5);
    Scheduler& scheduler = farm_.scheduler();
    std::string last_sent;
    absl::Time last_time = absl::InfinitePast();
    // Taken before each read, so a change during the read or the pause is never missed.
    uint64_t version = scheduler.WaitForChange(0, absl::InfinitePast());
    while (!context->IsCancelled()) {
        absl::StatusOr<JobRecord> job = scheduler.Get(req->job_id());
        if (!job.ok()) return ToGrpcStatus(job.status());
        pb::Job message;
        ToProto(*job, &message);
        std::string bytes = message.SerializeAsString();
        if (bytes != last_sent || absl::Now() - last_time > kMaxGap) {
            if (!writer->Write(message)) break;
            last_sent = std::move(bytes);
            last_time = absl::Now();
        }
        if (IsFinal(job->state)) break;
        absl::SleepFor(kMinGap);
        version = scheduler.WaitForChange(version, absl::Now() + absl::Seconds(1));
    }
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::CancelJob(grpc::ServerContext*, const pb::CancelJobRequest* req,
                                       pb::Job* resp) {
    absl::StatusOr<JobRecord> job = farm_.scheduler().Cancel(req->job_id());
    if (!job.ok()) return ToGrpcStatus(job.status());
    ToProto(*job, resp);
    return grpc::Status::OK;
}

grpc::Status JobServiceImpl::FetchResult(grpc::ServerContext* context,
                                         const pb::FetchResultRequest* req,
                                         grpc::ServerWriter<pb::Chunk>* writer) {
    absl::StatusOr<std::string> path = farm_.ResultFile(req->job_id(), req->preview());
    if (!path.ok()) return ToGrpcStatus(path.status());
    return StreamFile(context, *path, writer);
}

grpc::Status WorkerServiceImpl::LeaseTask(grpc::ServerContext*, const pb::LeaseTaskRequest* req,
                                          pb::LeaseTaskResponse* resp) {
    if (req->worker_id().empty()) {
        return ToGrpcStatus(absl::InvalidArgumentError("LeaseTask: worker_id is empty"));
    }
    const absl::Duration wait = absl::Milliseconds(std::clamp(req->wait_ms(), 0, 10000));
    if (std::optional<Lease> lease =
            farm_.scheduler().LeaseTask(req->worker_id(), absl::Now() + wait)) {
        ToProto(*lease, farm_.options(), resp->mutable_task());
    }
    return grpc::Status::OK;
}

grpc::Status WorkerServiceImpl::Heartbeat(grpc::ServerContext*, const pb::HeartbeatRequest* req,
                                          pb::HeartbeatResponse* resp) {
    resp->set_cancelled(!farm_.scheduler().Heartbeat(req->lease_id(), req->worker_id()));
    return grpc::Status::OK;
}

grpc::Status WorkerServiceImpl::CompleteTask(grpc::ServerContext*,
                                             const pb::CompleteTaskRequest* req,
                                             pb::CompleteTaskResponse*) {
    const absl::Status s =
        req->radiosity_sweep().empty()
            ? farm_.Complete(req->lease_id(), req->worker_id(), req->tile_sums())
            : farm_.CompleteSweep(req->lease_id(), req->worker_id(), req->radiosity_sweep());
    if (!s.ok())
        Log()->warn("lease={} CompleteTask refused: {}", req->lease_id(), std::string(s.message()));
    return ToGrpcStatus(s);
}

grpc::Status WorkerServiceImpl::FailTask(grpc::ServerContext*, const pb::FailTaskRequest* req,
                                         pb::FailTaskResponse*) {
    const FailureKind kind = req->kind() == pb::FailTaskRequest::WORKER_SHUTDOWN
                                 ? FailureKind::kWorkerShutdown
                                 : FailureKind::kTaskError;
    return ToGrpcStatus(
        farm_.scheduler().Fail(req->lease_id(), req->worker_id(), req->reason(), kind));
}

grpc::Status WorkerServiceImpl::FetchBlob(grpc::ServerContext* context,
                                          const pb::FetchBlobRequest* req,
                                          grpc::ServerWriter<pb::Chunk>* writer) {
    if (!farm_.blobs().Has(req->hash())) {
        return ToGrpcStatus(absl::NotFoundError("no blob " + req->hash()));
    }
    return StreamFile(context, farm_.blobs().PathOf(req->hash()), writer);
}

}  // namespace lf
