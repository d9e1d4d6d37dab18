// The gRPC services of lightfarm-server: thin adapters that convert between protobuf messages
// and the plain types of Farm and Scheduler. All protobuf conversion of the server is here.
#pragma once

#include <functional>
#include <string>
#include <string_view>

#include "lf/server/auth.h"
#include "lf/server/farm.h"
#include "lf/server/read_after_auth.h"
#include "lf/server/stream_slots.h"
#include "lightfarm/v1/job_service.grpc.pb.h"
#include "lightfarm/v1/worker_service.grpc.pb.h"

namespace lf {

// Who may call (lf/server/auth.h), for both services.

struct JobServiceOptions {
    // WatchJob streams open at once; each holds one of the server's threads while it lasts.
    int max_watchers = 256;
    // Streams one token may hold open at once, below the farm-wide bounds (the watchers above,
    // the blob store's kMaxPartialUploads), so that one token's stalled streams leave room for
    // other tokens'. Not applied with authentication off (every caller is the same anonymous
    // admin).
    int max_watchers_per_token = 32;
    int max_uploads_per_token = 4;
    int max_fetches_per_token = 4;
};

// ListJobs pages: the size when the request names none, and the largest.
constexpr int kDefaultPageSize = 100;
constexpr int kMaxPageSize = 1000;

// Handlers run with the caller already checked (lf/server/read_after_auth.h).
class JobServiceImpl final : public ReadAfterAuth<lightfarm::v1::JobService::Service> {
  public:
    JobServiceImpl(Farm& farm, CallGuard guard, JobServiceOptions options = {});

    // Client streaming: the handler checks the caller before it reads the first chunk.
    grpc::Status UploadBlob(grpc::ServerContext*,
                            grpc::ServerReader<lightfarm::v1::UploadBlobRequest>*,
                            lightfarm::v1::UploadBlobResponse*) override;

  private:
    grpc::Status MissingBlobs(grpc::ServerContext*, const Caller&,
                              const lightfarm::v1::MissingBlobsRequest&,
                              lightfarm::v1::MissingBlobsResponse*);
    grpc::Status BlobUploadOffset(grpc::ServerContext*, const Caller&,
                                  const lightfarm::v1::BlobUploadOffsetRequest&,
                                  lightfarm::v1::BlobUploadOffsetResponse*);
    grpc::Status SubmitJob(grpc::ServerContext*, const Caller&,
                           const lightfarm::v1::SubmitJobRequest&,
                           lightfarm::v1::SubmitJobResponse*);
    grpc::Status GetJob(grpc::ServerContext*, const Caller&, const lightfarm::v1::GetJobRequest&,
                        lightfarm::v1::Job*);
    grpc::Status ListJobs(grpc::ServerContext*, const Caller&,
                          const lightfarm::v1::ListJobsRequest&, lightfarm::v1::ListJobsResponse*);
    grpc::Status WatchJob(grpc::ServerContext*, const Caller&,
                          const lightfarm::v1::WatchJobRequest&,
                          const std::function<bool(const lightfarm::v1::Job&)>&);
    grpc::Status CancelJob(grpc::ServerContext*, const Caller&,
                           const lightfarm::v1::CancelJobRequest&, lightfarm::v1::Job*);
    grpc::Status SetJobPriority(grpc::ServerContext*, const Caller&,
                                const lightfarm::v1::SetJobPriorityRequest&, lightfarm::v1::Job*);
    // Worker management and stats (issue 30)
    grpc::Status SetWorkerState(grpc::ServerContext*, const Caller&,
                                const lightfarm::v1::SetWorkerStateRequest&,
                                lightfarm::v1::SetWorkerStateResponse*);
    // Job management (issue 30).
    grpc::Status RequeueJob(grpc::ServerContext*, const Caller&,
                            const lightfarm::v1::RequeueJobRequest&, lightfarm::v1::Job*);
    grpc::Status PauseJob(grpc::ServerContext*, const Caller&,
                          const lightfarm::v1::PauseJobRequest&, lightfarm::v1::Job*);
    grpc::Status ResumeJob(grpc::ServerContext*, const Caller&,
                           const lightfarm::v1::ResumeJobRequest&, lightfarm::v1::Job*);
    // History (issue 30).
    grpc::Status GetStats(grpc::ServerContext*, const Caller&,
                          const lightfarm::v1::GetStatsRequest&, lightfarm::v1::GetStatsResponse*);
    // Dependencies (issue 30).
    grpc::Status AddJobDependencies(grpc::ServerContext*, const Caller&,
                                    const lightfarm::v1::AddJobDependenciesRequest&,
                                    lightfarm::v1::Job*);
    // NotFound, as VisibleJob answers, for a job of `after` the caller may not see; the ids
    // checked by CheckDependencyIds first.
    absl::Status CheckVisibleDependencies(const Caller& caller,
                                          const std::vector<std::string>& after) const;
    // PauseJob and ResumeJob.
    grpc::Status SetPaused(grpc::ServerContext* context, const Caller& caller,
                           const std::string& job_id, bool paused, lightfarm::v1::Job* resp);
    grpc::Status FetchResult(grpc::ServerContext*, const Caller&,
                             const lightfarm::v1::FetchResultRequest&,
                             const std::function<bool(const lightfarm::v1::Chunk&)>&);
    grpc::Status DeleteJob(grpc::ServerContext*, const Caller&,
                           const lightfarm::v1::DeleteJobRequest&,
                           lightfarm::v1::DeleteJobResponse*);
    grpc::Status ListWorkers(grpc::ServerContext*, const Caller&,
                             const lightfarm::v1::ListWorkersRequest&,
                             lightfarm::v1::ListWorkersResponse*);
    grpc::Status ListTasks(grpc::ServerContext*, const Caller&,
                           const lightfarm::v1::ListTasksRequest&,
                           lightfarm::v1::ListTasksResponse*);
    grpc::Status GetTaskLogs(grpc::ServerContext*, const Caller&,
                             const lightfarm::v1::GetTaskLogsRequest&,
                             lightfarm::v1::GetTaskLogsResponse*);

    // The job if `caller` may see it; NotFound, as for a job that does not exist, otherwise, so
    // that job ids of others tell nothing.
    absl::StatusOr<JobRecord> VisibleJob(const Caller& caller, const std::string& job_id) const;

    Farm& farm_;
    StreamSlots watchers_, uploads_, fetches_;
};

// The log line of a refused result, every value from the wire escaped (lf::LogSafe).
std::string RefusedResultLine(std::string_view lease_id, std::string_view worker_id,
                              std::string_view peer, std::string_view why);

class WorkerServiceImpl final : public ReadAfterAuth<lightfarm::v1::WorkerService::Service> {
  public:
    WorkerServiceImpl(Farm& farm, CallGuard guard);

  private:
    grpc::Status LeaseTask(grpc::ServerContext*, const Caller&,
                           const lightfarm::v1::LeaseTaskRequest&,
                           lightfarm::v1::LeaseTaskResponse*);
    grpc::Status Heartbeat(grpc::ServerContext*, const Caller&,
                           const lightfarm::v1::HeartbeatRequest&,
                           lightfarm::v1::HeartbeatResponse*);
    grpc::Status CompleteTask(grpc::ServerContext*, const Caller&,
                              const lightfarm::v1::CompleteTaskRequest&,
                              lightfarm::v1::CompleteTaskResponse*);
    grpc::Status FailTask(grpc::ServerContext*, const Caller&,
                          const lightfarm::v1::FailTaskRequest&, lightfarm::v1::FailTaskResponse*);
    grpc::Status FetchBlob(grpc::ServerContext*, const Caller&,
                           const lightfarm::v1::FetchBlobRequest&,
                           const std::function<bool(const lightfarm::v1::Chunk&)>&);

    Farm& farm_;
};

}  // namespace lf
