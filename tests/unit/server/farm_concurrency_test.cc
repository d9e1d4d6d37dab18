// The coordinator's concurrency without gRPC, for ThreadSanitizer (deploy/sanitize.sh): a Farm
// with its SQLite store and timeout checker, driven at once by submitters (request ids repeated
// across threads and owners), workers (results, duplicates, failures, abandoned leases, second
// leases of stragglers), a canceller, a priority changer and readers. Whatever the interleaving,
// every job ends, each one not cancelled succeeds with every task merged once, and the lists
// agree at the end.
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <set>
#include <sstream>
#include <thread>
#include <vector>

#include "absl/strings/str_cat.h"
#include "lease_results.h"
#include "lf/core/image_io.h"
#include "lf/core/tile_codec.h"
#include "lf/job/digest.h"
#include "lf/server/farm.h"
#include "lf/server/timeout_checker.h"
#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

constexpr int kSpp = 4;
constexpr int kRequestIds = 12;         // per owner, each submitted by both of its threads
constexpr int kAnonymousPerThread = 6;  // submissions without a request id
constexpr int kWorkers = 6;
const std::vector<std::string> kOwners = {"alice", "bob"};

// The jobs submitted so far, shared by every thread.
class Submitted {
  public:
    void Add(const std::string& owner, const std::string& request_id, const std::string& id) {
        std::lock_guard<std::mutex> lock(mutex_);
        ids_.push_back(id);
        if (!request_id.empty()) answers_[{owner, request_id}].push_back(id);
        owners_[id] = owner;
    }
    // Any job submitted so far, or "" before the first.
    std::string Any(std::mt19937& random) const {
        std::lock_guard<std::mutex> lock(mutex_);
        if (ids_.empty()) return "";
        return ids_[std::uniform_int_distribution<size_t>(0, ids_.size() - 1)(random)];
    }
    std::map<std::string, std::string> owners() const {
        std::lock_guard<std::mutex> lock(mutex_);
        return owners_;
    }
    std::map<std::pair<std::string, std::string>, std::vector<std::string>> answers() const {
        std::lock_guard<std::mutex> lock(mutex_);
        return answers_;
    }

  private:
    mutable std::mutex mutex_;
    std::vector<std::string> ids_;  // one per successful Submit: repeats included
    std::map<std::pair<std::string, std::string>, std::vector<std::string>> answers_;
    std::map<std::string, std::string> owners_;  // by job id
};

class FarmConcurrencyTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = lf::testing::FreshTestDir("lf_farmconcurrency");
        FarmOptions options;
        options.data_dir = dir_.string();
        options.scheduler.lease = absl::Milliseconds(500);
        options.scheduler.speculate_after = absl::Milliseconds(20);  // second leases happen
        absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
        ASSERT_TRUE(farm.ok()) << farm.status();
        farm_ = std::move(*farm);
        // The Cornell box at 16x16: one task of 16x16 or four of 8x8.
        std::stringstream text;
        text << std::ifstream(fs::path(LF_TEST_SCENES) / "cornell_box.json").rdbuf();
        nlohmann::json scene = nlohmann::json::parse(text.str());
        scene["camera"]["resolution"] = {16, 16};
        const std::string json = scene.dump();
        scene_ = {"scene.json", Sha256Hex(json), json.size()};
        absl::StatusOr<std::unique_ptr<BlobStore::Upload>> upload =
            farm_->StartUpload(scene_.hash, scene_.size);
        ASSERT_TRUE(upload.ok()) << upload.status();
        ASSERT_TRUE((*upload)->Append(json).ok());
        ASSERT_TRUE((*upload)->Finish().ok());
    }

    void TearDown() override {
        farm_.reset();
        fs::remove_all(dir_);
    }

    // Job `n` of a submitter: 1 or 4 tasks, every third adaptive with a time limit short
    // enough to be enforced while it runs.
    JobSpec Spec(const std::string& owner, const std::string& request_id, int n) const {
        JobSpec spec;
        spec.name = absl::StrCat(owner, "-", n);
        spec.scene = scene_;
        spec.plan.spp = kSpp;
        spec.plan.tile = n % 2 ? 16 : 8;
        spec.plan.passes = 1;
        if (n % 3 == 0) spec.adaptive = {.target_error = 0.01, .time_limit = 0.05, .max_spp = 16};
        spec.priority = n % 3;
        spec.request_id = request_id;
        spec.owner = owner;
        // Failures here are chance, not the job's fault, nor a worker's.
        spec.max_attempts = spec.blocklist_after = kMaxAttemptsLimit;
        return spec;
    }

    void SubmitAll(const std::string& owner, int thread) {
        for (int n = 0; n < kRequestIds + kAnonymousPerThread; ++n) {
            const std::string request_id = n < kRequestIds ? absl::StrCat("r", n) : "";
            absl::StatusOr<std::string> id = farm_->Submit(Spec(owner, request_id, n));
            ASSERT_TRUE(id.ok()) << owner << " thread " << thread << " job " << n << ": "
                                 << id.status();
            submitted_.Add(owner, request_id, *id);
        }
    }

    // Leases and answers until told to stop: mostly an honest result after a heartbeat and a
    // log line, sometimes twice, sometimes late (a straggler), sometimes a failure or nothing.
    void Work(int index) {
        const std::string worker = absl::StrCat("w", index);
        std::mt19937 random(index);
        while (!stop_workers_) {
            std::optional<TaskAssignment> lease =
                farm_->scheduler().LeaseTask(worker, absl::Now() + absl::Milliseconds(20));
            if (!lease) continue;
            const int roll = std::uniform_int_distribution<int>(0, 99)(random);
            if (roll < 3) continue;  // abandoned: the timeout checker expires it
            if (roll < 8) {
                const FailureKind kind =
                    roll < 6 ? FailureKind::kTaskError : FailureKind::kWorkerShutdown;
                EXPECT_TRUE(farm_->scheduler().Fail(lease->lease_id, worker, "chance", kind).ok());
                continue;
            }
            farm_->scheduler().Heartbeat(lease->lease_id, worker);
            TaskLogLine line;
            line.task = lease->task.index;
            line.worker = worker;
            line.time = absl::Now();
            line.level = "info";
            line.text = "rendering";
            EXPECT_TRUE(farm_->TakeTaskLog(lease->lease_id, worker, {line}).ok());
            if (roll < 15) absl::SleepFor(absl::Milliseconds(40));  // a straggler
            const std::string result = EncodeTileSums(testing::UniformResult(*lease, Rgb(0.5f)));
            for (int times = roll < 25 ? 2 : 1; times > 0; --times) {
                // Refused only when the job ended meanwhile (cancelled, or done by another
                // lease of the task): never for the result itself.
                const absl::Status s = farm_->Complete(lease->lease_id, worker, result);
                EXPECT_TRUE(s.ok() || absl::IsFailedPrecondition(s))
                    << worker << " job " << lease->job_id << " task " << lease->task.index << ": "
                    << s;
            }
        }
    }

    void CancelSome() {
        std::mt19937 random(100);
        while (!stop_others_) {
            absl::SleepFor(absl::Milliseconds(15));
            const std::string id = submitted_.Any(random);
            if (id.empty() || random() % 4) continue;
            const absl::StatusOr<JobRecord> cancelled = farm_->scheduler().Cancel(id);
            if (cancelled.ok()) {
                EXPECT_EQ(cancelled->state, JobState::kCancelled) << id;
                std::lock_guard<std::mutex> lock(cancelled_mutex_);
                ++cancelled_[id];
            } else {
                EXPECT_TRUE(absl::IsFailedPrecondition(cancelled.status())) << cancelled.status();
            }
        }
    }

    void ChangePriorities() {
        std::mt19937 random(200);
        while (!stop_others_) {
            const std::string id = submitted_.Any(random);
            if (id.empty()) continue;
            const absl::StatusOr<JobRecord> changed = farm_->SetPriority(id, int(random() % 5) - 2);
            EXPECT_TRUE(changed.ok() || absl::IsFailedPrecondition(changed.status()))
                << changed.status();
            absl::SleepFor(absl::Milliseconds(2));
        }
    }

    // Every question a client, the dashboard or /metrics asks, all the time.
    void Read(int index) {
        std::mt19937 random(300 + index);
        Scheduler& scheduler = farm_->scheduler();
        uint64_t version = 0;
        while (!stop_others_) {
            version = scheduler.WaitForChange(version, absl::Now() + absl::Milliseconds(5));
            const std::string id = submitted_.Any(random);
            EXPECT_TRUE(scheduler.List().ok());
            EXPECT_TRUE(scheduler.List({.limit = 5, .owner = "alice"}).ok());
            scheduler.Workers();
            scheduler.Load();
            scheduler.BlobsInUse();
            scheduler.metrics().task_seconds.snapshot();  // /metrics reads without the lock
            scheduler.metrics().tasks_done.LastHour(absl::Now());
            if (id.empty()) continue;
            EXPECT_TRUE(scheduler.Get(id).ok()) << id;
            EXPECT_TRUE(farm_->Tasks(id).ok()) << id;
            EXPECT_TRUE(farm_->TaskLogs(id, std::nullopt, 0, 0).ok()) << id;
            scheduler.Snapshot(id).IgnoreError();  // ended meanwhile: FailedPrecondition
            const absl::StatusOr<std::string> file = farm_->ResultFile(id, true);
            EXPECT_TRUE(file.ok() || absl::IsFailedPrecondition(file.status())) << file.status();
        }
    }

    bool AllEnded(const std::map<std::string, std::string>& owners) {
        for (const auto& [id, owner] : owners) {
            absl::StatusOr<JobRecord> job = farm_->scheduler().Get(id);
            if (!job.ok() || !IsFinal(job->state)) return false;
        }
        return true;
    }

    fs::path dir_;
    std::unique_ptr<Farm> farm_;
    BlobRef scene_;
    Submitted submitted_;
    std::atomic<bool> stop_workers_{false}, stop_others_{false};
    std::mutex cancelled_mutex_;
    std::map<std::string, int> cancelled_;  // successful Cancel calls by job id
};

TEST_F(FarmConcurrencyTest, EveryJobEndsOnceWithEveryTaskMergedOnce) {
    std::vector<std::thread> submitters, others;
    for (const std::string& owner : kOwners) {
        for (int t = 0; t < 2; ++t) submitters.emplace_back([&, owner, t] { SubmitAll(owner, t); });
    }
    std::vector<std::thread> workers;
    for (int w = 0; w < kWorkers; ++w) workers.emplace_back([&, w] { Work(w); });
    others.emplace_back([&] { CancelSome(); });
    others.emplace_back([&] { ChangePriorities(); });
    for (int r = 0; r < 2; ++r) others.emplace_back([&, r] { Read(r); });
    {
        TimeoutChecker checker(absl::Milliseconds(10), [&] { farm_->CheckTimers(); });
        for (std::thread& t : submitters) t.join();
        const std::map<std::string, std::string> owners = submitted_.owners();
        // Generous for a loaded machine under ThreadSanitizer; the jobs end in seconds.
        const absl::Time deadline = absl::Now() + absl::Seconds(120);
        while (!AllEnded(owners) && absl::Now() < deadline) absl::SleepFor(absl::Milliseconds(20));
        stop_others_ = true;
        for (std::thread& t : others) t.join();
        stop_workers_ = true;
        for (std::thread& t : workers) t.join();
    }

    // Request ids: one job per owner and id, whichever thread asked and how often.
    const std::map<std::string, std::string> owners = submitted_.owners();
    std::map<std::string, std::set<std::string>> by_request;  // job ids by request id name
    for (const auto& [key, ids] : submitted_.answers()) {
        const auto& [owner, request_id] = key;
        EXPECT_EQ(ids.size(), 2u);
        EXPECT_EQ(std::set<std::string>(ids.begin(), ids.end()).size(), 1u)
            << owner << "'s request " << request_id << " made more than one job";
        by_request[request_id].insert(ids[0]);
        EXPECT_EQ(farm_->scheduler().Get(ids[0])->spec.request_id,
                  absl::StrCat(owner, "/", request_id));
    }
    for (const auto& [request_id, ids] : by_request) {
        EXPECT_EQ(ids.size(), kOwners.size()) << request_id << ": one job for each owner";
    }
    const size_t jobs = kOwners.size() * (kRequestIds + 2 * kAnonymousPerThread);
    ASSERT_EQ(owners.size(), jobs);

    // Every job ended: cancelled if a Cancel said so (once), else succeeded with each task
    // merged once: kSpp samples in every pixel.
    int cancelled = 0, succeeded = 0;
    for (const auto& [id, owner] : owners) {
        const absl::StatusOr<JobRecord> job = farm_->scheduler().Get(id);
        ASSERT_TRUE(job.ok()) << id << ": " << job.status();
        EXPECT_EQ(job->spec.owner, owner);
        const int cancels = cancelled_.count(id) ? cancelled_[id] : 0;
        EXPECT_LE(cancels, 1) << id << " was cancelled twice";
        if (cancels) {
            EXPECT_EQ(job->state, JobState::kCancelled) << id;
            ++cancelled;
            continue;
        }
        ASSERT_EQ(job->state, JobState::kSucceeded) << id << ": " << job->error;
        ++succeeded;
        EXPECT_EQ(job->tasks_done, job->tasks_total) << id;
        EXPECT_EQ(job->tasks_running, 0) << id;
        const absl::StatusOr<std::vector<TaskStatus>> tasks = farm_->Tasks(id);
        ASSERT_TRUE(tasks.ok()) << tasks.status();
        EXPECT_EQ(int(tasks->size()), job->tasks_total) << id;
        for (const TaskStatus& task : *tasks) {
            EXPECT_EQ(task.state, TaskStatus::State::kDone) << id << " task " << task.index;
        }
        const absl::StatusOr<ExrFile> exr = ReadExr(job->result_path);
        ASSERT_TRUE(exr.ok()) << id << ": " << exr.status();
        const std::vector<float>* spp = exr->image.FindChannel("spp");
        ASSERT_NE(spp, nullptr) << id;
        for (size_t i = 0; i < spp->size(); ++i) {
            ASSERT_EQ((*spp)[i], float(kSpp)) << id << " pixel " << i;
        }
    }
    std::printf("%zu jobs: %d succeeded, %d cancelled\n", owners.size(), succeeded, cancelled);

    // The lists agree with the jobs, and nothing is left running.
    const absl::StatusOr<std::vector<JobRecord>> all = farm_->scheduler().List();
    ASSERT_TRUE(all.ok()) << all.status();
    EXPECT_EQ(all->size(), jobs);
    for (const JobRecord& job : *all) {
        EXPECT_EQ(owners.count(job.id), 1u) << job.id;
        EXPECT_TRUE(IsFinal(job.state)) << job.id;
    }
    for (const std::string& owner : kOwners) {
        const absl::StatusOr<std::vector<JobRecord>> own =
            farm_->scheduler().List({.owner = owner});
        ASSERT_TRUE(own.ok()) << own.status();
        EXPECT_EQ(own->size(), jobs / kOwners.size()) << owner;
        for (const JobRecord& job : *own) EXPECT_EQ(job.spec.owner, owner);
    }
    for (const WorkerStatus& worker : farm_->scheduler().Workers()) {
        EXPECT_FALSE(worker.busy()) << worker.id << " holds " << worker.job_id;
    }
    const SchedulerLoad load = farm_->scheduler().Load();
    EXPECT_EQ(load.jobs_queued + load.jobs_running, 0);
    EXPECT_EQ(load.tasks_queued + load.tasks_running, 0);
    EXPECT_EQ(load.workers_busy, 0);
}

}  // namespace
}  // namespace lf
