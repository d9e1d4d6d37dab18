// The worker's side of the wire: calls to the server's WorkerService with a deadline each, in
// plain types. All protobuf conversion of the worker is here.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "lf/core/film.h"
#include "lf/job/render_metadata.h"
#include "lf/job/task_assignment.h"
#include "lf/job/task_status.h"
#include "lf/proto/channel.h"

namespace lf {

class ServerConnection {
  public:
    // Connects lazily; after the server restarts, calls work again within about a second.
    // InvalidArgument or NotFound naming the flag for TLS or token files that cannot be used.
    // `name` is for people (lightfarm workers); the server tells workers apart by `worker_id`.
    static absl::StatusOr<std::unique_ptr<ServerConnection>> Open(const ChannelOptions& options,
                                                                  std::string worker_id,
                                                                  std::string name = "");
    ~ServerConnection();

    const std::string& worker_id() const { return worker_id_; }
    // Sent with every lease request: the server leases only jobs whose tags the worker all has
    // (lightfarm-worker --tags, checked by lf::CheckTags).
    void set_tags(std::vector<std::string> tags) { tags_ = std::move(tags); }

    // Waits up to `wait` for work; nullopt: none.
    absl::StatusOr<std::optional<TaskAssignment>> Lease(absl::Duration wait);
    // False: stop the task (its job was cancelled or the lease is gone). `log`: the task's
    // lines captured since the last heartbeat.
    absl::StatusOr<bool> Heartbeat(const std::string& lease_id, std::vector<TaskLogLine> log);
    // Encoded TileSums, or a sweep task's lf::EncodeSweepResult.
    struct TaskResult {
        std::string bytes;
        bool sweep = false;
        std::optional<RadiosityFigures> radiosity;  // a radiosity job's tile: for the EXR header
        // A splat task's splat list (lf::EncodeSplatList); `bytes` is then its camera part.
        std::optional<std::string> splats;
        std::vector<TaskLogLine> log;  // the task's lines no heartbeat took
        std::optional<int> frame;      // a shot's task: the frame rendered
        // A chunk of a shot: one result a part of the lease, in its order, instead of `bytes`.
        struct Part {
            int frame = 0;
            std::string bytes;
            std::optional<std::string> splats;
            TaskTimes times;  // the part's own
        };
        std::vector<Part> parts;
        TaskTimes times;  // the whole lease's (issue 30's history)
    };
    absl::Status Complete(const std::string& lease_id, const TaskResult& result, double seconds);
    // `shutdown`: the worker is stopping, which does not count against the task.
    absl::Status Fail(const std::string& lease_id, const std::string& reason, bool shutdown,
                      std::vector<TaskLogLine> log);
    // Writes blob `hash` to `path`.
    absl::Status FetchBlob(const std::string& hash, const std::string& path);

  private:
    ServerConnection(std::string worker_id, std::string name);
    std::string worker_id_;
    std::string name_;
    std::vector<std::string> tags_;
    struct Stub;  // keeps gRPC headers out of the worker's other files
    std::unique_ptr<Stub> stub_;
};

}  // namespace lf
