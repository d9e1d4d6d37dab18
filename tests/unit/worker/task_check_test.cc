// A worker given a malformed task (a noise-threshold pass whose mask of active pixels does not
// fit its tile or its job) fails it with a message naming what is wrong, before any download,
// and keeps working.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <optional>
#include <thread>

#include "lf/worker/worker.h"
#include "lightfarm/v1/worker_service.grpc.pb.h"

namespace lf {
namespace {

namespace fs = std::filesystem;
namespace pb = lightfarm::v1;

// Leases one task, then none; records the failure the worker reports.
class OneTaskService final : public pb::WorkerService::Service {
  public:
    explicit OneTaskService(pb::Task task) : task_(std::move(task)) {}

    grpc::Status LeaseTask(grpc::ServerContext*, const pb::LeaseTaskRequest*,
                           pb::LeaseTaskResponse* response) override {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!leased_) *response->mutable_task() = task_;
        leased_ = true;
        return grpc::Status::OK;
    }
    grpc::Status Heartbeat(grpc::ServerContext*, const pb::HeartbeatRequest*,
                           pb::HeartbeatResponse*) override {
        return grpc::Status::OK;
    }
    grpc::Status FailTask(grpc::ServerContext*, const pb::FailTaskRequest* request,
                          pb::FailTaskResponse*) override {
        std::lock_guard<std::mutex> lock(mutex_);
        failure_ = request->reason();
        changed_.notify_all();
        return grpc::Status::OK;
    }
    grpc::Status CompleteTask(grpc::ServerContext*, const pb::CompleteTaskRequest*,
                              pb::CompleteTaskResponse*) override {
        std::lock_guard<std::mutex> lock(mutex_);
        failure_ = "completed";
        changed_.notify_all();
        return grpc::Status::OK;
    }
    std::string WaitForFailure() {
        std::unique_lock<std::mutex> lock(mutex_);
        changed_.wait(lock, [&] { return failure_.has_value(); });
        return *failure_;
    }

  private:
    pb::Task task_;
    std::mutex mutex_;
    std::condition_variable changed_;
    bool leased_ = false;
    std::optional<std::string> failure_;
};

// Runs a worker against a service leasing `task`; the reason it gives for failing it.
std::string FailureOf(const pb::Task& task) {
    OneTaskService service(task);
    grpc::ServerBuilder builder;
    int port = 0;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
    builder.RegisterService(&service);
    std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
    EXPECT_TRUE(server && port > 0);
    const fs::path dir =
        fs::temp_directory_path() / ("lf_task_check_" + std::to_string(::getpid()));
    absl::StatusOr<std::unique_ptr<BlobCache>> cache = BlobCache::Open(dir.string(), 1 << 20);
    EXPECT_TRUE(cache.ok()) << cache.status();
    absl::StatusOr<std::unique_ptr<ServerConnection>> connection =
        ServerConnection::Open({.address = "127.0.0.1:" + std::to_string(port)}, "w");
    EXPECT_TRUE(connection.ok()) << connection.status();
    WorkerOptions options;
    options.lease_wait = absl::Milliseconds(10);
    TaskLogSink logs;
    Worker worker(options, **connection, **cache, logs);
    std::thread run([&] { worker.Run(); });
    const std::string failure = service.WaitForFailure();
    worker.Stop();
    run.join();
    server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
    fs::remove_all(dir);
    return failure;
}

// A 10x2 tile of a path-traced job with a noise threshold, samples 64..80 of the pixels in
// `mask` (the scene is never fetched: the check comes first).
pb::Task MaskedTask(const std::string& mask, uint64_t max_spp = 4096) {
    pb::Task task;
    task.set_lease_id("lease-1");
    task.set_job_id("job-1");
    task.set_task_index(3);
    task.mutable_scene()->set_path("scene.json");
    task.mutable_scene()->set_hash(std::string(64, 'a'));
    task.mutable_params()->set_method("path");
    task.mutable_params()->set_spp(64);
    task.mutable_params()->set_noise_threshold(0.01);
    task.mutable_params()->set_max_spp(max_spp);
    task.set_width(10);
    task.set_height(2);
    task.set_sample_begin(64);
    task.set_sample_end(80);
    task.set_active_pixels(mask);
    return task;
}

TEST(WorkerTaskCheck, RefusesAMaskOfTheWrongLength) {
    EXPECT_EQ(FailureOf(MaskedTask(std::string("\x01", 1))),
              "task 3: active pixels: 1 bytes, expected 3 (one bit per pixel of 10x2)");
}

TEST(WorkerTaskCheck, RefusesSamplesBeyondTheJobsMaxSpp) {
    EXPECT_EQ(FailureOf(MaskedTask(std::string("\x01\x00\x00", 3), 72)),
              "task 3: active pixels: samples up to 80, beyond the job's max_spp 72");
}

}  // namespace
}  // namespace lf
