#include "server/grpc_service.h"

#include <algorithm>
#include <fstream>

#include "absl/strings/str_cat.h"
#include "lf/core/log.h"
#include "lf/version.h"
#include "lf/wire/conversions.h"
#include "proto/grpc_status.h"

namespace lf {

namespace pb = lightfarm::v1;

namespace {

constexpr size_t kChunkBytes = 1 << 20;

std::shared_ptr<spdlog::logger> Log() { return NamedLogger("rpc"); }

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
    if (req->version() != kBuildVersion) {
        return ToGrpcStatus(absl::FailedPreconditionError(absl::StrCat(
            "worker version ", req->version().empty() ? "(none)" : req->version(),
            ", server version ", kBuildVersion, ": run workers of the server's build")));
    }
    const absl::Duration wait = absl::Milliseconds(std::clamp(req->wait_ms(), 0, 10000));
    if (std::optional<TaskAssignment> lease =
            farm_.scheduler().LeaseTask(req->worker_id(), absl::Now() + wait)) {
        ToProto(*lease, resp->mutable_task());
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
