// The gRPC services of lightfarm-server: thin adapters that convert between protobuf messages
// and the plain types of Farm and Scheduler. All protobuf conversion of the server is here.
#pragma once

#include <atomic>
#include <string>
#include <string_view>

#include "lightfarm/v1/job_service.grpc.pb.h"
#include "lightfarm/v1/worker_service.grpc.pb.h"
#include "lf/server/auth.h"
#include "lf/server/farm.h"

namespace lf {

// Who may call (lf/server/auth.h), for both services.
struct CallGuard {
    Authenticator& auth;
    // With mutual TLS (lightfarm-server --tls-client-ca): WorkerService calls must come with a
    // client certificate the CA signed, besides a worker token.
    bool worker_certificates = false;

    // The caller of `rpc` if it may take `action`; UNAUTHENTICATED or PERMISSION_DENIED with the
    // reason otherwise, and the refusal logged with the peer.
    absl::StatusOr<Caller> Check(grpc::ServerContext* context, const char* rpc,
                                 Action action) const;
};

struct JobServiceOptions {
    // WatchJob streams open at once; each holds one of the server's threads while it lasts.
    int max_watchers = 256;
};

// ListJobs pages: the size when the request names none, and the largest.
constexpr int kDefaultPageSize = 100;
constexpr int kMaxPageSize = 1000;

class JobServiceImpl final : public lightfarm::v1::JobService::Service {
  public:
    JobServiceImpl(Farm& farm, CallGuard guard, JobServiceOptions options = {})
        : farm_(farm), guard_(guard), options_(options) {}

    grpc::Status MissingBlobs(grpc::ServerContext*, const lightfarm::v1::MissingBlobsRequest*,
                              lightfarm::v1::MissingBlobsResponse*) override;
    grpc::Status BlobUploadOffset(grpc::ServerContext*,
                                  const lightfarm::v1::BlobUploadOffsetRequest*,
                                  lightfarm::v1::BlobUploadOffsetResponse*) override;
    grpc::Status UploadBlob(grpc::ServerContext*,
                            grpc::ServerReader<lightfarm::v1::UploadBlobRequest>*,
                            lightfarm::v1::UploadBlobResponse*) override;
    grpc::Status SubmitJob(grpc::ServerContext*, const lightfarm::v1::SubmitJobRequest*,
                           lightfarm::v1::SubmitJobResponse*) override;
    grpc::Status GetJob(grpc::ServerContext*, const lightfarm::v1::GetJobRequest*,
                        lightfarm::v1::Job*) override;
    grpc::Status ListJobs(grpc::ServerContext*, const lightfarm::v1::ListJobsRequest*,
                          lightfarm::v1::ListJobsResponse*) override;
    grpc::Status WatchJob(grpc::ServerContext*, const lightfarm::v1::WatchJobRequest*,
                          grpc::ServerWriter<lightfarm::v1::Job>*) override;
    grpc::Status CancelJob(grpc::ServerContext*, const lightfarm::v1::CancelJobRequest*,
                           lightfarm::v1::Job*) override;
    grpc::Status SetJobPriority(grpc::ServerContext*,
                                const lightfarm::v1::SetJobPriorityRequest*,
                                lightfarm::v1::Job*) override;
    grpc::Status FetchResult(grpc::ServerContext*, const lightfarm::v1::FetchResultRequest*,
                             grpc::ServerWriter<lightfarm::v1::Chunk>*) override;
    grpc::Status DeleteJob(grpc::ServerContext*, const lightfarm::v1::DeleteJobRequest*,
                           lightfarm::v1::DeleteJobResponse*) override;
    grpc::Status ListWorkers(grpc::ServerContext*, const lightfarm::v1::ListWorkersRequest*,
                             lightfarm::v1::ListWorkersResponse*) override;
    grpc::Status ListTasks(grpc::ServerContext*, const lightfarm::v1::ListTasksRequest*,
                           lightfarm::v1::ListTasksResponse*) override;
    grpc::Status GetTaskLogs(grpc::ServerContext*, const lightfarm::v1::GetTaskLogsRequest*,
                             lightfarm::v1::GetTaskLogsResponse*) override;

  private:
    // The job if `caller` may see it; NotFound, as for a job that does not exist, otherwise, so
    // that job ids of others tell nothing.
    absl::StatusOr<JobRecord> VisibleJob(const Caller& caller, const std::string& job_id) const;

    Farm& farm_;
    const CallGuard guard_;
    const JobServiceOptions options_;
    std::atomic<int> watchers_{0};
};

// The log line of a refused result, every value from the wire escaped (lf::LogSafe).
std::string RefusedResultLine(std::string_view lease_id, std::string_view worker_id,
                              std::string_view peer, std::string_view why);

class WorkerServiceImpl final : public lightfarm::v1::WorkerService::Service {
  public:
    WorkerServiceImpl(Farm& farm, CallGuard guard) : farm_(farm), guard_(guard) {}

    grpc::Status LeaseTask(grpc::ServerContext*, const lightfarm::v1::LeaseTaskRequest*,
                           lightfarm::v1::LeaseTaskResponse*) override;
    grpc::Status Heartbeat(grpc::ServerContext*, const lightfarm::v1::HeartbeatRequest*,
                           lightfarm::v1::HeartbeatResponse*) override;
    grpc::Status CompleteTask(grpc::ServerContext*, const lightfarm::v1::CompleteTaskRequest*,
                              lightfarm::v1::CompleteTaskResponse*) override;
    grpc::Status FailTask(grpc::ServerContext*, const lightfarm::v1::FailTaskRequest*,
                          lightfarm::v1::FailTaskResponse*) override;
    grpc::Status FetchBlob(grpc::ServerContext*, const lightfarm::v1::FetchBlobRequest*,
                           grpc::ServerWriter<lightfarm::v1::Chunk>*) override;

  private:
    Farm& farm_;
    const CallGuard guard_;
};

}  // namespace lf
