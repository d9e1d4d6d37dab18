// Server and workers of different builds: the server leases only to workers of its own build
// (lf::kBuildVersion) and refuses any other, an empty version included, with FAILED_PRECONDITION
// naming both versions; a refused worker keeps retrying, so upgrading either side is enough.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <thread>

#include "lf/version.h"
#include "lf/server/grpc_service.h"
#include "lf/worker/worker.h"

namespace lf {
namespace {

namespace fs = std::filesystem;
namespace pb = lightfarm::v1;

class WorkerVersionTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("lf_version_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        FarmOptions options;
        options.data_dir = dir_.string();
        absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
        ASSERT_TRUE(farm.ok()) << farm.status();
        farm_ = std::move(*farm);
        service_ = std::make_unique<WorkerServiceImpl>(*farm_, CallGuard{*auth_});
        jobs_ = std::make_unique<JobServiceImpl>(*farm_, CallGuard{*auth_});
        grpc::ServerBuilder builder;
        int port = 0;
        builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
        builder.RegisterService(service_.get());
        builder.RegisterService(jobs_.get());
        server_ = builder.BuildAndStart();
        ASSERT_TRUE(server_ && port > 0);
        address_ = "127.0.0.1:" + std::to_string(port);
        stub_ = pb::WorkerService::NewStub(
            grpc::CreateChannel(address_, grpc::InsecureChannelCredentials()));
    }

    void TearDown() override {
        farm_->scheduler().Shutdown();
        server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
        fs::remove_all(dir_);
    }

    grpc::Status Lease(const std::string& version, const std::string& name = "") {
        pb::LeaseTaskRequest request;
        request.set_worker_id("w");
        request.set_version(version);
        request.set_name(name);
        pb::LeaseTaskResponse response;
        grpc::ClientContext context;
        context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
        context.set_wait_for_ready(true);
        return stub_->LeaseTask(&context, request, &response);
    }

    fs::path dir_;
    std::unique_ptr<Farm> farm_;
    std::unique_ptr<Authenticator> auth_ = Authenticator::Off();
    std::unique_ptr<WorkerServiceImpl> service_;
    std::unique_ptr<JobServiceImpl> jobs_;
    std::unique_ptr<grpc::Server> server_;
    std::string address_;
    std::unique_ptr<pb::WorkerService::Stub> stub_;
};

TEST_F(WorkerVersionTest, WorkerOfAnotherBuildIsRefusedNamingBothVersions) {
    const grpc::Status other = Lease("0.0.9 (protocol 0, v0.0.9)");
    EXPECT_EQ(other.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
    EXPECT_NE(other.error_message().find(absl::StrCat("worker version 0.0.9 (protocol 0, v0.0.9), "
                                                      "server version ",
                                                      kBuildVersion)),
              std::string::npos)
        << other.error_message();
}

TEST_F(WorkerVersionTest, WorkerWithoutVersionIsRefused) {
    const grpc::Status none = Lease("");
    EXPECT_EQ(none.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
    EXPECT_NE(none.error_message().find("worker version (none), server version"), std::string::npos)
        << none.error_message();
}

TEST_F(WorkerVersionTest, WorkerOfThisBuildIsServed) {
    EXPECT_TRUE(Lease(kBuildVersion).ok());
    absl::StatusOr<std::unique_ptr<ServerConnection>> connection =
        ServerConnection::Open({.address = address_}, "real-worker");
    ASSERT_TRUE(connection.ok()) << connection.status();
    const absl::StatusOr<std::optional<TaskAssignment>> lease =
        (*connection)->Lease(absl::Milliseconds(10));
    EXPECT_TRUE(lease.ok()) << lease.status();
}

TEST_F(WorkerVersionTest, ServedWorkerIsListedWithItsNameAddressAndVersion) {
    absl::StatusOr<std::unique_ptr<ServerConnection>> connection =
        ServerConnection::Open({.address = address_}, "real-worker", "render-07");
    ASSERT_TRUE(connection.ok()) << connection.status();
    ASSERT_TRUE((*connection)->Lease(absl::Milliseconds(10)).ok());
    const auto jobs =
        pb::JobService::NewStub(grpc::CreateChannel(address_, grpc::InsecureChannelCredentials()));
    pb::ListWorkersResponse listed;
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    ASSERT_TRUE(jobs->ListWorkers(&context, pb::ListWorkersRequest(), &listed).ok());
    ASSERT_EQ(listed.workers_size(), 1);
    const pb::WorkerInfo& w = listed.workers(0);
    EXPECT_EQ(w.id(), "real-worker");
    EXPECT_EQ(w.name(), "render-07");
    EXPECT_EQ(w.address().rfind("ipv4:127.0.0.1:", 0), 0u) << w.address();
    EXPECT_EQ(w.version(), kBuildVersion);
    EXPECT_EQ(w.state(), pb::WorkerInfo::IDLE);  // nothing to lease
    EXPECT_GE(w.seconds_since_seen(), 0);
    EXPECT_LT(w.seconds_since_seen(), 30);
}

TEST_F(WorkerVersionTest, WorkerNameAboveTheLimitIsRefused) {
    const grpc::Status s = Lease(kBuildVersion, std::string(kMaxWorkerNameBytes + 1, 'n'));
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_TRUE(Lease(kBuildVersion, std::string(kMaxWorkerNameBytes, 'n')).ok());
}

// A server of another build: every lease is refused. The worker keeps asking (with backoff)
// rather than exiting, until it is stopped.
class RefusingService final : public pb::WorkerService::Service {
  public:
    grpc::Status LeaseTask(grpc::ServerContext*, const pb::LeaseTaskRequest* req,
                           pb::LeaseTaskResponse*) override {
        std::lock_guard<std::mutex> lock(mutex_);
        versions_.push_back(req->version());
        changed_.notify_all();
        return grpc::Status(grpc::StatusCode::FAILED_PRECONDITION,
                            "worker version " + req->version() + ", server version 9.9.9");
    }
    std::vector<std::string> WaitForLeases(size_t n) {
        std::unique_lock<std::mutex> lock(mutex_);
        changed_.wait(lock, [&] { return versions_.size() >= n; });
        return versions_;
    }

  private:
    std::mutex mutex_;
    std::condition_variable changed_;
    std::vector<std::string> versions_;
};

TEST(WorkerVersionRetry, RefusedWorkerKeepsRetryingWithItsVersionUntilStopped) {
    RefusingService service;
    grpc::ServerBuilder builder;
    int port = 0;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
    builder.RegisterService(&service);
    std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
    ASSERT_TRUE(server && port > 0);

    const fs::path dir = fs::temp_directory_path() / ("lf_version_w_" + std::to_string(::getpid()));
    absl::StatusOr<std::unique_ptr<BlobCache>> cache = BlobCache::Open(dir.string(), 1 << 20);
    ASSERT_TRUE(cache.ok()) << cache.status();
    absl::StatusOr<std::unique_ptr<ServerConnection>> connection =
        ServerConnection::Open({.address = "127.0.0.1:" + std::to_string(port)}, "old-worker");
    ASSERT_TRUE(connection.ok()) << connection.status();
    WorkerOptions options;
    options.min_idle = absl::Milliseconds(1);
    options.max_idle = absl::Milliseconds(8);
    TaskLogSink logs;
    Worker worker(options, **connection, **cache, logs);
    std::thread run([&] { worker.Run(); });
    const std::vector<std::string> versions = service.WaitForLeases(3);
    worker.Stop();
    run.join();
    for (const std::string& v : versions) EXPECT_EQ(v, kBuildVersion);
    server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
    fs::remove_all(dir);
}

}  // namespace
}  // namespace lf
