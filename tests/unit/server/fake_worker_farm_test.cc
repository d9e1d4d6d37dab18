// A real server in this process with fake workers and clients speaking the protocol through
// gRPC stubs. Workers that misbehave: a result for a task the worker does not hold, an
// undecodable or wrong-sized result, a worker that never heartbeats, and a straggler; none may
// change a job's pixels: each job's EXR must equal that of a job rendered by honest workers
// alone. And load: many clients submitting and watching at once. The fake workers' "render" is a
// fixed function of (pixel, sample), so no renderer is needed.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

#include "lf/core/image_io.h"
#include "lf/core/log.h"
#include "lf/core/tile_codec.h"
#include "lf/job/digest.h"
#include "lf/server/grpc_service.h"
#include "lf/version.h"
#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;
namespace pb = lightfarm::v1;

std::string ReadText(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

class FakeWorkerFarm : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = lf::testing::FreshTestDir("lf_fakefarm");
        FarmOptions options;
        options.data_dir = dir_.string();
        options.scheduler.lease = absl::Milliseconds(500);
        options.scheduler.speculate_after = speculate_after_;
        absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
        ASSERT_TRUE(farm.ok()) << farm.status();
        farm_ = std::move(*farm);
        jobs_ = std::make_unique<JobServiceImpl>(*farm_, CallGuard{*auth_}, service_options_);
        workers_ = std::make_unique<WorkerServiceImpl>(*farm_, CallGuard{*auth_});
        grpc::ServerBuilder builder;
        int port = 0;
        builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
        builder.RegisterService(jobs_.get());
        builder.RegisterService(workers_.get());
        server_ = builder.BuildAndStart();
        ASSERT_TRUE(server_ && port > 0);
        address_ = "127.0.0.1:" + std::to_string(port);
        auto channel = NewChannel();
        job_stub_ = pb::JobService::NewStub(channel);
        worker_stub_ = pb::WorkerService::NewStub(channel);
        checker_ = std::thread([this] {
            while (!stop_) {
                farm_->scheduler().ExpireLeases();
                std::this_thread::sleep_for(std::chrono::milliseconds(20));
            }
        });
        PutSceneBlob();
    }

    void TearDown() override {
        stop_ = true;
        checker_.join();
        farm_->scheduler().Shutdown();
        server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
        fs::remove_all(dir_);
    }

    // The Cornell box at 16x16, so 4 tasks of 8x8 pixels.
    void PutSceneBlob() {
        nlohmann::json scene =
            nlohmann::json::parse(ReadText(fs::path(LF_TEST_SCENES) / "cornell_box.json"));
        scene["camera"]["resolution"] = {16, 16};
        scene_json_ = scene.dump();
        scene_hash_ = Sha256Hex(scene_json_);
        absl::StatusOr<std::unique_ptr<BlobStore::Upload>> upload =
            farm_->blobs().StartUpload(scene_hash_, scene_json_.size());
        ASSERT_TRUE(upload.ok()) << upload.status();
        ASSERT_TRUE((*upload)->Append(scene_json_).ok());
        ASSERT_TRUE((*upload)->Finish().ok());
    }

    std::string Submit(pb::JobService::Stub* stub = nullptr, int tile = 8) {
        pb::SubmitJobRequest request = SubmitRequest(tile);
        pb::SubmitJobResponse response;
        // As a client should: a deadline, and waiting out a connection the loaded machine did
        // not make at once (seen under ctest -j2: "failed to connect to all addresses").
        grpc::ClientContext context;
        context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
        context.set_wait_for_ready(true);
        const grpc::Status s =
            (stub ? stub : job_stub_.get())->SubmitJob(&context, request, &response);
        EXPECT_TRUE(s.ok()) << s.error_message();
        return response.job_id();
    }

    pb::SubmitJobRequest SubmitRequest(int tile = 8) {
        pb::SubmitJobRequest request;
        request.mutable_scene()->set_path("scene.json");
        request.mutable_scene()->set_hash(scene_hash_);
        request.mutable_scene()->set_size(scene_json_.size());
        request.mutable_params()->set_spp(4);
        request.mutable_params()->set_tile(tile);
        request.mutable_params()->set_passes(1);
        return request;
    }

    pb::Job GetJob(const std::string& id) {
        pb::GetJobRequest request;
        request.set_job_id(id);
        pb::Job job;
        grpc::ClientContext context;
        EXPECT_TRUE(job_stub_->GetJob(&context, request, &job).ok());
        return job;
    }

    std::optional<pb::Task> Lease(const std::string& worker, int wait_ms = 0) {
        pb::LeaseTaskRequest request;
        request.set_version(kBuildVersion);
        request.set_worker_id(worker);
        request.set_wait_ms(wait_ms);
        pb::LeaseTaskResponse response;
        grpc::ClientContext context;
        EXPECT_TRUE(worker_stub_->LeaseTask(&context, request, &response).ok());
        if (!response.has_task()) return std::nullopt;
        return response.task();
    }

    bool Heartbeat(const pb::Task& task, const std::string& worker) {
        pb::HeartbeatRequest request;
        request.set_lease_id(task.lease_id());
        request.set_worker_id(worker);
        pb::HeartbeatResponse response;
        grpc::ClientContext context;
        EXPECT_TRUE(worker_stub_->Heartbeat(&context, request, &response).ok());
        return !response.cancelled();
    }

    // A fresh connection, as another client process would have.
    std::shared_ptr<grpc::Channel> NewChannel() {
        grpc::ChannelArguments args;
        args.SetInt("lightfarm.test.channel", ++channels_);  // no sharing of connections
        return grpc::CreateCustomChannel(address_, grpc::InsecureChannelCredentials(), args);
    }

    grpc::Status Complete(const std::string& lease_id, const std::string& worker,
                          const std::string& bytes) {
        pb::CompleteTaskRequest request;
        request.set_lease_id(lease_id);
        request.set_worker_id(worker);
        request.set_tile_sums(bytes);
        pb::CompleteTaskResponse response;
        grpc::ClientContext context;
        return worker_stub_->CompleteTask(&context, request, &response);
    }

    // What an honest worker sends for `task`: a fixed function of (pixel, sample).
    static std::string HonestResult(const pb::Task& task) {
        TileSums sums(PixelRect{task.x0(), task.y0(), task.width(), task.height()});
        for (int y = 0; y < task.height(); ++y) {
            for (int x = 0; x < task.width(); ++x) {
                PixelSums& p = sums.pixels[size_t(y * task.width() + x)];
                for (uint64_t s = task.sample_begin(); s < task.sample_end(); ++s) {
                    p.Add(s, Rgb(float((task.x0() + x) * 7 + (task.y0() + y) * 3 + s) / 64.0f));
                }
            }
        }
        return EncodeTileSums(sums);
    }

    // An honest worker takes and completes tasks until the job has ended.
    void RenderHonestly(const std::string& job_id, const std::string& worker = "honest") {
        for (int i = 0; i < 50 && !IsEnded(job_id); ++i) {
            if (std::optional<pb::Task> task = Lease(worker, 200)) {
                ASSERT_TRUE(Complete(task->lease_id(), worker, HonestResult(*task)).ok());
            }
        }
        ASSERT_EQ(GetJob(job_id).state(), pb::Job::SUCCEEDED) << GetJob(job_id).error();
    }
    bool IsEnded(const std::string& job_id) {
        const pb::Job::State s = GetJob(job_id).state();
        return s != pb::Job::QUEUED && s != pb::Job::RUNNING;
    }

    // The job's pixels equal those of a job rendered by an honest worker alone.
    void ExpectSameAsHonest(const std::string& job_id) {
        const std::string reference = Submit();
        RenderHonestly(reference);
        absl::StatusOr<std::string> a = farm_->ResultFile(job_id, false);
        absl::StatusOr<std::string> b = farm_->ResultFile(reference, false);
        ASSERT_TRUE(a.ok() && b.ok());
        absl::StatusOr<ExrFile> x = ReadExr(*a), y = ReadExr(*b);
        ASSERT_TRUE(x.ok() && y.ok());
        for (const char* ch : {"R", "G", "B", "spp"}) {
            const std::vector<float>& u = *x->image.FindChannel(ch);
            const std::vector<float>& v = *y->image.FindChannel(ch);
            ASSERT_EQ(u.size(), v.size());
            EXPECT_EQ(0, std::memcmp(u.data(), v.data(), u.size() * sizeof(float))) << ch;
        }
    }

    // A client's watch of a job: its last message read, and its status once it ended.
    struct Watching {
        grpc::ClientContext context;
        std::unique_ptr<grpc::ClientReader<pb::Job>> reader;
        pb::Job last;
        bool open = false;  // its first message came
        grpc::Status ReadToEnd() {
            while (reader->Read(&last)) {
            }
            return reader->Finish();
        }
    };
    void OpenWatch(const std::string& job_id, Watching& w) {
        w.context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
        pb::WatchJobRequest request;
        request.set_job_id(job_id);
        w.reader = job_stub_->WatchJob(&w.context, request);
        w.open = w.reader->Read(&w.last);
    }

    absl::Duration speculate_after_ = absl::Seconds(30);  // no speculation but in StragglerTest
    JobServiceOptions service_options_;
    fs::path dir_;
    std::unique_ptr<Farm> farm_;
    std::unique_ptr<Authenticator> auth_ = Authenticator::Off();
    std::unique_ptr<JobServiceImpl> jobs_;
    std::unique_ptr<WorkerServiceImpl> workers_;
    std::unique_ptr<grpc::Server> server_;
    std::unique_ptr<pb::JobService::Stub> job_stub_;
    std::unique_ptr<pb::WorkerService::Stub> worker_stub_;
    std::string address_;
    std::atomic<int> channels_{0};
    std::atomic<bool> stop_{false};
    std::thread checker_;
    std::string scene_json_, scene_hash_;
};

TEST_F(FakeWorkerFarm, ResultForATaskTheWorkerDoesNotHoldIsRefused) {
    const std::string job = Submit();
    const pb::Task task = *Lease("honest");
    const grpc::Status stolen = Complete(task.lease_id(), "liar", HonestResult(task));
    EXPECT_EQ(stolen.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
    const grpc::Status forged =
        Complete(task.job_id() + "/" + std::to_string(task.task_index() + 1) + "/x-1", "liar",
                 HonestResult(task));
    EXPECT_EQ(forged.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
    EXPECT_EQ(GetJob(job).tasks_done(), 0);
    EXPECT_TRUE(Heartbeat(task, "honest"));
    ASSERT_TRUE(Complete(task.lease_id(), "honest", HonestResult(task)).ok());
    RenderHonestly(job);
    ExpectSameAsHonest(job);
}

TEST_F(FakeWorkerFarm, CorruptAndWrongSizedResultsAreRefusedAndTheTaskRequeued) {
    const std::string job = Submit();
    Lease("honest");  // seen alive, so a refused task goes to it rather than back to the liar
    const pb::Task first = *Lease("liar");
    std::string corrupt = HonestResult(first);
    corrupt[corrupt.size() / 2] ^= 0x5a;
    corrupt.resize(corrupt.size() - 3);
    EXPECT_EQ(Complete(first.lease_id(), "liar", corrupt).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_EQ(GetJob(job).retries(), 1);
    EXPECT_FALSE(Heartbeat(first, "liar")) << "the refused lease is over";

    const pb::Task second = *Lease("liar");
    pb::Task bigger = second;
    bigger.set_width(second.width() + 1);
    EXPECT_EQ(Complete(second.lease_id(), "liar", HonestResult(bigger)).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_EQ(GetJob(job).retries(), 2);
    EXPECT_EQ(GetJob(job).tasks_done(), 0);
    // The first honest lease above expires unheard; everything is rendered again honestly.
    RenderHonestly(job);
    ExpectSameAsHonest(job);
}

// A worker's failure reason is kept with the task, as the job's last error and in its
// blocklist, saved with every record write and printed by the CLI: a reason near the request
// limit, with newlines, is kept as one escaped line of at most 1 KiB in each.
TEST_F(FakeWorkerFarm, AHugeFailureReasonIsKeptAsOneBoundedLine) {
    const std::string job = Submit();
    const pb::Task task = *Lease("flaky");
    std::string reason;
    while (reason.size() < (size_t(4) << 20) - 4096) reason += "out of memory\nat line 7\n";
    pb::FailTaskRequest request;
    request.set_lease_id(task.lease_id());
    request.set_worker_id("flaky");
    request.set_reason(reason);
    pb::FailTaskResponse response;
    grpc::ClientContext context;
    ASSERT_TRUE(worker_stub_->FailTask(&context, request, &response).ok());

    const absl::StatusOr<JobRecord> record = farm_->scheduler().Get(job);
    ASSERT_TRUE(record.ok()) << record.status();
    ASSERT_EQ(record->worker_failures.size(), 1u);
    const std::optional<std::vector<TaskStatus>> tasks = farm_->scheduler().Tasks(job);
    ASSERT_TRUE(tasks.has_value());
    const std::string task_error = (*tasks)[size_t(task.task_index())].last_error;
    // Each as the scheduler words it: the reason with a short prefix or suffix.
    for (const std::string* kept :
         {&task_error, &record->last_error, &record->worker_failures[0].last_error}) {
        EXPECT_EQ(kept->find('\n'), std::string::npos) << *kept;
        EXPECT_NE(kept->find("out of memory"), std::string::npos);
        EXPECT_LE(kept->size(), 1024u + 64) << kept->substr(0, 80);
    }
    EXPECT_EQ(GetJob(job).last_error().size(), record->last_error.size());
}

// RequeueJob's frames: parsed as submit's --frames, each refusal naming what was wrong.
TEST_F(FakeWorkerFarm, RequeueJobFramesAreCheckedAndNamedInTheError) {
    const std::string job = Submit();
    RenderHonestly(job);
    const auto requeue = [&](const std::string& frames) {
        pb::RequeueJobRequest request;
        request.set_job_id(job);
        request.set_frames(frames);
        pb::Job response;
        grpc::ClientContext context;
        return job_stub_->RequeueJob(&context, request, &response);
    };
    const grpc::Status reversed = requeue("5-2");
    EXPECT_EQ(reversed.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_EQ(reversed.error_message().rfind("frames: ", 0), 0u) << reversed.error_message();
    const grpc::Status huge = requeue(std::string(1 << 20, '7'));
    EXPECT_EQ(huge.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_LT(huge.error_message().size(), 200u);
    const grpc::Status still = requeue("1-2");
    EXPECT_EQ(still.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(still.error_message().find("still image"), std::string::npos)
        << still.error_message();
    EXPECT_EQ(GetJob(job).state(), pb::Job::SUCCEEDED);
}

// A bound on the wait for a task to be leased again (after a 500 ms lease, or 300 ms of
// straggling): far above that, so that a loaded machine does not fail the tests.
constexpr std::chrono::seconds kLeasedAgainWithin{30};

TEST_F(FakeWorkerFarm, SilentWorkerLosesItsLeaseAndTheTaskIsLeasedAgain) {
    const std::string job = Submit();
    const pb::Task silent = *Lease("silent");
    const auto start = std::chrono::steady_clock::now();
    std::optional<pb::Task> again;
    while (!again && std::chrono::steady_clock::now() - start < kLeasedAgainWithin) {
        std::optional<pb::Task> task = Lease("honest", 200);
        if (!task) continue;
        if (task->task_index() == silent.task_index()) again = task;
        ASSERT_TRUE(Complete(task->lease_id(), "honest", HonestResult(*task)).ok());
    }
    ASSERT_TRUE(again) << "the silent worker's task was never leased again";
    EXPECT_FALSE(Heartbeat(silent, "silent"));
    RenderHonestly(job);
    EXPECT_GE(GetJob(job).retries(), 1);
    ExpectSameAsHonest(job);
}

class StragglerTest : public FakeWorkerFarm {
  protected:
    StragglerTest() { speculate_after_ = absl::Milliseconds(300); }
};

TEST_F(StragglerTest, StragglersTaskIsLeasedAgainAndTheFirstResultWins) {
    const std::string job = Submit();
    const pb::Task slow = *Lease("slow");
    std::optional<pb::Task> copy;
    const auto start = std::chrono::steady_clock::now();
    while (!copy && std::chrono::steady_clock::now() - start < kLeasedAgainWithin) {
        EXPECT_TRUE(Heartbeat(slow, "slow"));  // alive, just slow
        std::optional<pb::Task> task = Lease("fast", 100);
        if (!task) continue;
        if (task->task_index() == slow.task_index()) {
            copy = task;
        } else {
            ASSERT_TRUE(Complete(task->lease_id(), "fast", HonestResult(*task)).ok());
        }
    }
    ASSERT_TRUE(copy) << "the straggler's task was never leased again";
    ASSERT_TRUE(Complete(copy->lease_id(), "fast", HonestResult(*copy)).ok());
    EXPECT_EQ(GetJob(job).state(), pb::Job::SUCCEEDED);
    EXPECT_FALSE(Heartbeat(slow, "slow")) << "the straggler is told to stop";
    // Its late result comes after the job ended, and changes nothing.
    EXPECT_EQ(Complete(slow.lease_id(), "slow", HonestResult(slow)).error_code(),
              grpc::StatusCode::FAILED_PRECONDITION);
    ExpectSameAsHonest(job);
}

TEST_F(FakeWorkerFarm, TwentyClientsTwoHundredJobsAWatcherEachNothingLost) {
    constexpr int kClients = 20, kJobsPerClient = 10, kJobs = kClients * kJobsPerClient;
    std::mutex mutex;
    std::vector<std::string> ids;
    std::vector<std::thread> threads;
    std::atomic<int> succeeded{0}, watch_errors{0};
    auto watch = [&](std::string id) {
        auto stub = pb::JobService::NewStub(NewChannel());
        grpc::ClientContext context;
        context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
        pb::WatchJobRequest request;
        request.set_job_id(id);
        auto reader = stub->WatchJob(&context, request);
        pb::Job job;
        pb::Job::State last = pb::Job::STATE_UNSPECIFIED;
        while (reader->Read(&job)) last = job.state();
        if (!reader->Finish().ok()) ++watch_errors;
        if (last == pb::Job::SUCCEEDED) ++succeeded;
    };
    const auto start = std::chrono::steady_clock::now();
    std::vector<std::thread> clients;
    for (int c = 0; c < kClients; ++c) {
        clients.emplace_back([&] {
            auto stub = pb::JobService::NewStub(NewChannel());
            for (int j = 0; j < kJobsPerClient; ++j) {
                const std::string id = Submit(stub.get(), /*tile=*/16);  // one task
                std::lock_guard<std::mutex> lock(mutex);
                ids.push_back(id);
                threads.emplace_back(watch, id);
            }
        });
    }
    std::vector<std::thread> workers;
    for (int w = 0; w < 2; ++w) {
        workers.emplace_back([&, w] {
            const std::string name = "worker-" + std::to_string(w);
            while (succeeded < kJobs &&
                   std::chrono::steady_clock::now() - start < std::chrono::seconds(60)) {
                if (std::optional<pb::Task> task = Lease(name, 100)) {
                    EXPECT_TRUE(Complete(task->lease_id(), name, HonestResult(*task)).ok());
                }
            }
        });
    }
    for (std::thread& t : clients) t.join();
    for (std::thread& t : workers) t.join();
    for (std::thread& t : threads) t.join();
    std::printf("%d jobs submitted by %d clients, watched and done in %.1f s\n", kJobs, kClients,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    EXPECT_EQ(succeeded, kJobs);
    EXPECT_EQ(watch_errors, 0);
    std::sort(ids.begin(), ids.end());
    EXPECT_EQ(std::unique(ids.begin(), ids.end()), ids.end()) << "a job id was given twice";
    EXPECT_EQ(int(farm_->scheduler().List()->size()), kJobs);
}

TEST_F(FakeWorkerFarm, UploadStreamingMoreThanItDeclaredIsRefused) {
    const std::string content(3 << 20, 'x');
    grpc::ClientContext context;
    pb::UploadBlobResponse response;
    auto writer = job_stub_->UploadBlob(&context, &response);
    pb::UploadBlobRequest chunk;
    chunk.set_hash(Sha256Hex(content));
    chunk.set_size(10);  // a lie: it streams 3 MiB
    for (size_t offset = 0; offset < content.size(); offset += 1 << 20) {
        chunk.set_data(content.substr(offset, 1 << 20));
        if (!writer->Write(chunk)) break;
        chunk.clear_hash();
        chunk.clear_size();
    }
    writer->WritesDone();
    const grpc::Status s = writer->Finish();
    EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << s.error_message();
    EXPECT_NE(s.error_message().find("10 bytes declared"), std::string::npos) << s.error_message();
    EXPECT_FALSE(farm_->blobs().Has(Sha256Hex(content)));
}

TEST_F(FakeWorkerFarm, SubmissionDeclaringASmallerSizeThanItsBlobIsRefused) {
    // The scene size limit adds the declared sizes: they must be the blobs' own.
    pb::SubmitJobRequest request = SubmitRequest();
    request.mutable_scene()->set_size(1);
    pb::SubmitJobResponse response;
    grpc::ClientContext context;
    const grpc::Status s = job_stub_->SubmitJob(&context, request, &response);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(s.error_message().find("declared as 1 bytes"), std::string::npos)
        << s.error_message();
}

TEST_F(FakeWorkerFarm, AnUnknownPixelFilterIsRefusedNamingTheField) {
    pb::SubmitJobRequest request = SubmitRequest();
    request.mutable_params()->set_filter_type(static_cast<pb::PixelFilterType>(77));
    request.mutable_params()->set_filter_width(3);
    pb::SubmitJobResponse response;
    grpc::ClientContext context;
    const grpc::Status s = job_stub_->SubmitJob(&context, request, &response);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(s.error_message().find("params.filter_type 77"), std::string::npos)
        << s.error_message();
    EXPECT_TRUE(farm_->scheduler().List()->empty());
}

TEST_F(FakeWorkerFarm, AnUnknownSamplerOrLightStrategyIsRefusedNamingTheField) {
    const std::vector<std::pair<std::string, std::function<void(pb::RenderParams&)>>> cases = {
        {"params.sampler 77",
         [](pb::RenderParams& p) { p.set_sampler(static_cast<pb::SamplerType>(77)); }},
        {"params.light_strategy 77",
         [](pb::RenderParams& p) { p.set_light_strategy(static_cast<pb::LightStrategy>(77)); }},
    };
    for (const auto& [field, set] : cases) {
        pb::SubmitJobRequest request = SubmitRequest();
        set(*request.mutable_params());
        pb::SubmitJobResponse response;
        grpc::ClientContext context;
        const grpc::Status s = job_stub_->SubmitJob(&context, request, &response);
        EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << field;
        EXPECT_NE(s.error_message().find(field), std::string::npos) << s.error_message();
    }
    EXPECT_TRUE(farm_->scheduler().List()->empty());
}

TEST_F(FakeWorkerFarm, JobNameAndRequestIdAboveTheirLimitsAreRefused) {
    for (const bool name : {true, false}) {
        pb::SubmitJobRequest request = SubmitRequest();
        (name ? request.mutable_name() : request.mutable_request_id())
            ->assign(2 << 20, 'n');  // 2 MiB
        pb::SubmitJobResponse response;
        grpc::ClientContext context;
        const grpc::Status s = job_stub_->SubmitJob(&context, request, &response);
        EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
        EXPECT_NE(
            s.error_message().find(std::to_string(name ? kMaxJobNameBytes : kMaxRequestIdBytes)),
            std::string::npos)
            << s.error_message();
    }
    EXPECT_TRUE(farm_->scheduler().List()->empty());
}

TEST_F(FakeWorkerFarm, ListJobsPagesNewestFirstUntilTheLastPage) {
    std::vector<std::string> submitted;
    for (int i = 0; i < 5; ++i) submitted.insert(submitted.begin(), Submit());
    std::vector<std::string> listed;
    std::string token;
    int pages = 0;
    do {
        pb::ListJobsRequest request;
        request.set_page_size(2);
        request.set_page_token(token);
        pb::ListJobsResponse response;
        grpc::ClientContext context;
        ASSERT_TRUE(job_stub_->ListJobs(&context, request, &response).ok());
        EXPECT_LE(response.jobs_size(), 2);
        for (const pb::Job& job : response.jobs()) listed.push_back(job.id());
        token = response.next_page_token();
        ++pages;
    } while (!token.empty() && pages < 10);
    EXPECT_EQ(listed, submitted);
    EXPECT_EQ(pages, 3);

    pb::ListJobsRequest forged;
    forged.set_page_token("x");
    pb::ListJobsResponse response;
    grpc::ClientContext context;
    EXPECT_EQ(job_stub_->ListJobs(&context, forged, &response).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(FakeWorkerFarm, DeleteRemovesAnEndedJobAndRefusesARunningOne) {
    const std::string job = Submit();
    auto remove = [&](const std::string& id) {
        pb::DeleteJobRequest request;
        request.set_job_id(id);
        pb::DeleteJobResponse response;
        grpc::ClientContext context;
        return job_stub_->DeleteJob(&context, request, &response);
    };
    EXPECT_EQ(remove(job).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
    RenderHonestly(job);
    const std::string result = *farm_->ResultFile(job, false);
    ASSERT_TRUE(fs::exists(result));
    const grpc::Status deleted = remove(job);
    ASSERT_TRUE(deleted.ok()) << deleted.error_message();
    pb::GetJobRequest request;
    request.set_job_id(job);
    pb::Job got;
    grpc::ClientContext context;
    EXPECT_EQ(job_stub_->GetJob(&context, request, &got).error_code(), grpc::StatusCode::NOT_FOUND);
    EXPECT_FALSE(fs::exists(result));
    EXPECT_EQ(remove(job).error_code(), grpc::StatusCode::NOT_FOUND);
}

// A watch's last message goes out once the job's end is in the store: a client acting on it at
// once finds the job ended there, and may requeue it (not "has just ended": UNAVAILABLE).
TEST_F(FakeWorkerFarm, WatchEndsOnceTheJobsEndIsInTheStore) {
    const std::string job = Submit();
    ASSERT_TRUE(Lease("honest").has_value());
    Watching watch;
    OpenWatch(job, watch);
    ASSERT_TRUE(watch.open);
    EXPECT_EQ(watch.last.state(), pb::Job::RUNNING);
    std::thread cancel([&] {
        pb::CancelJobRequest cancel_request;
        cancel_request.set_job_id(job);
        pb::Job cancelled;
        grpc::ClientContext cancel_context;
        EXPECT_TRUE(job_stub_->CancelJob(&cancel_context, cancel_request, &cancelled).ok());
    });
    const grpc::Status watched = watch.ReadToEnd();
    absl::StatusOr<JobRecord> stored = farm_->store().Get(job);
    // Its tasks are recorded before the end goes out: `lightfarm tasks` lists them at once.
    absl::StatusOr<std::vector<TaskStatus>> tasks = farm_->Tasks(job);
    pb::RequeueJobRequest requeue_request;
    requeue_request.set_job_id(job);
    pb::Job requeued;
    grpc::ClientContext requeue_context;
    const grpc::Status requeue =
        job_stub_->RequeueJob(&requeue_context, requeue_request, &requeued);
    cancel.join();
    ASSERT_TRUE(watched.ok()) << watched.error_message();
    EXPECT_EQ(watch.last.state(), pb::Job::CANCELLED);
    ASSERT_TRUE(stored.ok()) << stored.status();
    EXPECT_EQ(stored->state, JobState::kCancelled);
    ASSERT_TRUE(tasks.ok()) << tasks.status();
    EXPECT_EQ(int(tasks->size()), stored->tasks_total);
    EXPECT_FALSE(tasks->empty());
    ASSERT_TRUE(requeue.ok()) << requeue.error_message();
    EXPECT_EQ(requeued.state(), pb::Job::QUEUED);
}

// A server shutting down ends the watches of running jobs at once (UNAVAILABLE: the client
// watches on after the restart), rather than when their clients' deadlines pass.
TEST_F(FakeWorkerFarm, ShutdownEndsAWatchAsUnavailable) {
    Watching watch;
    OpenWatch(Submit(), watch);
    ASSERT_TRUE(watch.open);
    farm_->scheduler().Shutdown();
    const grpc::Status watched = watch.ReadToEnd();
    EXPECT_EQ(watched.error_code(), grpc::StatusCode::UNAVAILABLE) << watched.error_message();
    EXPECT_EQ(watch.last.state(), pb::Job::QUEUED);
}

class WatcherCapTest : public FakeWorkerFarm {
  protected:
    WatcherCapTest() { service_options_.max_watchers = 2; }
};

TEST_F(WatcherCapTest, WatchBeyondTheCapIsRefusedAndOneEndingFreesItsSlot) {
    // The first message of a watch comes once its slot is taken.
    const std::string a = Submit(), b = Submit();
    Watching first, second, third;
    OpenWatch(a, first);
    OpenWatch(b, second);
    ASSERT_TRUE(first.open && second.open);
    OpenWatch(b, third);
    EXPECT_FALSE(third.open);
    const grpc::Status refused = third.reader->Finish();
    EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_NE(refused.error_message().find("--max-watchers"), std::string::npos)
        << refused.error_message();

    RenderHonestly(a);  // the first watch ends with its job
    ASSERT_TRUE(first.ReadToEnd().ok());
    Watching fourth;
    OpenWatch(b, fourth);
    EXPECT_TRUE(fourth.open) << "the ended watch's slot is free again";
    second.context.TryCancel();
    fourth.context.TryCancel();
    second.reader->Finish();
    fourth.reader->Finish();
}

TEST_F(FakeWorkerFarm, ForgedNewlineInAWorkerIdDoesNotReachTheLogRaw) {
    Submit();
    const pb::Task task = *Lease("honest");
    std::ostringstream captured;
    std::shared_ptr<spdlog::logger> log = NamedLogger("rpc");
    auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(captured);
    sink->set_pattern("%v");
    log->sinks().push_back(sink);
    const std::string forged = "liar\n[info] job=" + task.job_id() + " succeeded";
    EXPECT_EQ(Complete(task.lease_id(), forged, HonestResult(task)).error_code(),
              grpc::StatusCode::FAILED_PRECONDITION);
    log->flush();
    log->sinks().pop_back();
    const std::string text = captured.str();
    EXPECT_NE(text.find("worker=liar\\n[info] job="), std::string::npos) << text;
    EXPECT_EQ(text.find("liar\n"), std::string::npos) << text;
    EXPECT_NE(text.find("from ipv"), std::string::npos) << "the line names the peer: " << text;
    EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
}

// A worker's task log lines are kept under its lease's task and attempt only when it holds that
// lease; the last ones come with the result and are kept before the job ends with it, so a
// client that sees the job ended has every line.
TEST_F(FakeWorkerFarm, TaskLogLinesAreKeptOnlyFromTheLeasesWorkerAndBeforeItsJobEnds) {
    const std::string job = Submit(nullptr, /*tile=*/16);  // one task
    const pb::Task task = *Lease("honest");
    const auto heartbeat = [&](const std::string& lease_id, const std::string& worker,
                               const std::string& text) {
        pb::HeartbeatRequest request;
        request.set_lease_id(lease_id);
        request.set_worker_id(worker);
        pb::WorkerLogLine* line = request.add_log();
        line->set_unix_ms(1'700'000'000'000);
        line->set_level("info");
        line->set_text(text);
        pb::HeartbeatResponse response;
        grpc::ClientContext context;
        EXPECT_TRUE(worker_stub_->Heartbeat(&context, request, &response).ok());
    };
    heartbeat(task.lease_id(), "honest", "rendering");
    heartbeat(task.lease_id(), "liar", "forged by another worker");
    heartbeat(task.job_id() + "/0/x-1", "honest", "forged lease");

    pb::CompleteTaskRequest result;
    result.set_lease_id(task.lease_id());
    result.set_worker_id("honest");
    result.set_tile_sums(HonestResult(task));
    pb::WorkerLogLine* last = result.add_log();
    last->set_level("error");
    last->set_text("done");
    pb::CompleteTaskResponse completed;
    {
        grpc::ClientContext context;
        ASSERT_TRUE(worker_stub_->CompleteTask(&context, result, &completed).ok());
    }
    EXPECT_EQ(GetJob(job).state(), pb::Job::SUCCEEDED);

    pb::GetTaskLogsRequest request;
    request.set_job_id(job);
    pb::GetTaskLogsResponse logs;
    {
        grpc::ClientContext context;
        ASSERT_TRUE(job_stub_->GetTaskLogs(&context, request, &logs).ok());
    }
    ASSERT_EQ(logs.lines_size(), 2);
    EXPECT_EQ(logs.lines(0).text(), "rendering");
    EXPECT_EQ(logs.lines(0).unix_ms(), 1'700'000'000'000);
    EXPECT_EQ(logs.lines(1).text(), "done");
    EXPECT_EQ(logs.lines(1).level(), "error");
    for (const pb::TaskLogLine& line : logs.lines()) {
        EXPECT_EQ(line.task_index(), task.task_index());
        EXPECT_EQ(line.attempt(), 1);
        EXPECT_EQ(line.worker(), "honest");
    }
    EXPECT_EQ(logs.next_seq(), logs.lines(1).seq());
    EXPECT_TRUE(logs.job_ended());

    pb::ListTasksRequest list;
    list.set_job_id(job);
    pb::ListTasksResponse tasks;
    {
        grpc::ClientContext context;
        ASSERT_TRUE(job_stub_->ListTasks(&context, list, &tasks).ok());
    }
    ASSERT_EQ(tasks.tasks_size(), 1);
    EXPECT_EQ(tasks.tasks(0).state(), pb::TaskInfo::DONE);
    EXPECT_EQ(tasks.tasks(0).worker(), "honest");
    EXPECT_EQ(tasks.tasks(0).log_lines(), 2);

    request.set_job_id("job-0000000000");
    grpc::ClientContext context;
    EXPECT_EQ(job_stub_->GetTaskLogs(&context, request, &logs).error_code(),
              grpc::StatusCode::NOT_FOUND);
}

TEST(RefusedResultLineTest, EveryWireValueIsEscaped) {
    const std::string line = RefusedResultLine("lease\r1", "w\n2", "ipv4:1.2.3.4:5", "why\x1b");
    EXPECT_EQ(line,
              "lease=lease\\r1 worker=w\\n2 from ipv4:1.2.3.4:5: CompleteTask refused: why\\x1b");
}

}  // namespace
}  // namespace lf
