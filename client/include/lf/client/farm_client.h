// The farm commands' connection to lightfarm-server's JobService: every call with a deadline and
// the server's errors in words a user can act on, outages ridden out for --retry-seconds,
// resumable blob uploads, submission, and following a job and fetching its result.
#pragma once

#include <grpcpp/grpcpp.h>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "lf/client/farm_flags.h"
#include "lf/client/progress_bar.h"
#include "lf/job/job_spec.h"
#include "lf/proto/grpc_status.h"
#include "lightfarm/v1/job_service.grpc.pb.h"

namespace lf {

class FarmClient {
  public:
    // A unary call of JobService, as `&lightfarm::v1::JobService::Stub::GetJob`.
    template <typename Request, typename Response>
    using Rpc = grpc::Status (lightfarm::v1::JobService::Stub::*)(grpc::ClientContext*,
                                                                  const Request&, Response*);

    // Connects at once. A TLS or token file removed since the command line was checked
    // (AddServerOption) leaves nothing to retry with: exits with status 2, saying so.
    explicit FarmClient(const FarmFlags& flags);

    // One call with a 10 s deadline.
    template <typename Request, typename Response>
    absl::Status Call(Rpc<Request, Response> rpc, const Request& request, Response* response) {
        return CallStatus(
            (stub_.get()->*rpc)(ContextWithDeadline(absl::Seconds(10)).get(), request, response));
    }

    // Call, again on a new channel while the server is unreachable, for up to --retry-seconds;
    // `what` names the call in the messages said while waiting.
    template <typename Request, typename Response>
    absl::Status CallRetrying(const std::string& what, Rpc<Request, Response> rpc,
                              const Request& request, Response* response) {
        return Retrying(what, [&] {
            *response = Response();
            return Call(rpc, request, response);
        });
    }

    // Uploads what the server lacks of spec.scene and spec.files (`blobs`: their bytes by hash)
    // and submits the job, riding out outages; returns the job's id.
    absl::StatusOr<std::string> Submit(const JobSpec& spec,
                                       const std::map<std::string, std::string>& blobs);

    // Follows the job until it ends, showing its tasks done on `bar`, across server outages of up
    // to --retry-seconds; returns it as it ended.
    absl::StatusOr<lightfarm::v1::Job> Watch(const std::string& id, ProgressBar& bar);

    // The job's OpenEXR result (with `preview`, a running job's tiles merged so far) into `path`.
    // A shot's `frame`: that frame's EXR (with `preview`, what is merged of it so far).
    absl::Status FetchResult(const std::string& id, const std::string& path, bool preview,
                             std::optional<int> frame = std::nullopt);

  private:
    void Connect();
    absl::Status CallStatus(const grpc::Status& status) const;
    absl::Status Retrying(const std::string& what, const std::function<absl::Status()>& attempt,
                          bool (*transient)(const absl::Status&) = &absl::IsUnavailable);
    absl::Status SubmitOnce(const std::vector<BlobRef>& files,
                            const std::map<std::string, std::string>& blobs,
                            const lightfarm::v1::SubmitJobRequest& request, std::string* id);
    absl::Status Upload(const BlobRef& file, const std::string& content, uint64_t& sent,
                        uint64_t total, ProgressBar* bar);

    FarmFlags flags_;
    std::unique_ptr<lightfarm::v1::JobService::Stub> stub_;
};

// `lightfarm watch JOB` (and `submit --watch`, on the connection it submitted on): follows the
// job to its end, with a progress bar on a terminal, and prints how it ended; returns the exit
// status, 0 only when it succeeded.
int WatchJob(FarmClient& client, const std::string& job_id);

}  // namespace lf
