// lightfarm-server --notify-url: an ended job (succeeded, failed, cancelled) is POSTed as JSON
// to an httplib server here; one that hangs does not hold up the jobs' ends.
#include "lf/server/job_notifier.h"

#include <gtest/gtest.h>
#include <httplib.h>
#include <unistd.h>

#include <filesystem>
#include <future>
#include <nlohmann/json.hpp>

#include "lease_results.h"
#include "lf/server/farm.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

// An endpoint on a port of 127.0.0.1 that keeps every body POSTed to /ended, and holds each
// answer while `hang` is set.
class Endpoint {
  public:
    Endpoint() {
        server_.Post("/ended", [this](const httplib::Request& req, httplib::Response& res) {
            std::unique_lock<std::mutex> lock(mutex_);
            bodies_.push_back(nlohmann::json::parse(req.body));
            changed_.notify_all();
            changed_.wait(lock, [&] { return !hang_; });
            res.status = 204;
        });
        port_ = server_.bind_to_any_port("127.0.0.1");
        thread_ = std::thread([this] { server_.listen_after_bind(); });
    }
    ~Endpoint() {
        Hang(false);
        server_.stop();
        thread_.join();
    }
    std::string url() const { return "http://127.0.0.1:" + std::to_string(port_) + "/ended"; }
    void Hang(bool hang) {
        std::lock_guard<std::mutex> lock(mutex_);
        hang_ = hang;
        changed_.notify_all();
    }
    // Waits for `n` bodies (up to a minute: a bound for a broken test, not a timing).
    std::vector<nlohmann::json> Await(size_t n) {
        std::unique_lock<std::mutex> lock(mutex_);
        changed_.wait_for(lock, std::chrono::minutes(1), [&] { return bodies_.size() >= n; });
        return bodies_;
    }

  private:
    httplib::Server server_;
    int port_ = 0;
    std::thread thread_;
    std::mutex mutex_;
    std::condition_variable changed_;
    bool hang_ = false;
    std::vector<nlohmann::json> bodies_;
};

class JobNotifierTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("lf_notify_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        FarmOptions options;
        options.data_dir = dir_.string();
        options.notify_url = endpoint_.url();
        // Longer than any hang here (each test releases the endpoint itself): a post timed out
        // under a slow sanitizer run would be sent again and posted twice.
        options.notify.timeout = absl::Minutes(5);
        absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
        ASSERT_TRUE(farm.ok()) << farm.status();
        farm_ = std::move(*farm);
    }
    void TearDown() override {
        endpoint_.Hang(false);
        farm_.reset();
        fs::remove_all(dir_);
    }

    // A 2-task job queued straight in the scheduler (no scene: nothing renders it here).
    std::string Queue(const std::string& name) {
        JobSpec spec;
        spec.name = name;
        spec.owner = "alice";
        spec.plan = {16, 8, 1, 8, 1};
        absl::StatusOr<std::string> id = farm_->scheduler().Submit(spec);
        EXPECT_TRUE(id.ok()) << id.status();
        return *id;
    }
    // Merges every task of the job, as workers' results would; the run they rendered.
    Scheduler::JobRun RenderAll(const std::string& id) {
        Scheduler& s = farm_->scheduler();
        Scheduler::JobRun rendered{id};
        while (std::optional<TaskAssignment> lease = s.LeaseTask("w")) {
            EXPECT_EQ(lease->job_id, id);
            absl::StatusOr<Scheduler::Completion> done =
                s.Complete(lease->lease_id, "w", testing::UniformResult(*lease, Rgb(1)));
            EXPECT_TRUE(done.ok()) << done.status();
            if (done.ok()) rendered.run = done->run;
        }
        return rendered;
    }

    Endpoint endpoint_;
    fs::path dir_;
    std::unique_ptr<Farm> farm_;
};

TEST_F(JobNotifierTest, SucceededAndFailedJobsArePosted) {
    const std::string good = Queue("good");
    farm_->scheduler().Finish(RenderAll(good), std::string("/results/good.exr"));
    const std::string bad = Queue("bad");
    farm_->scheduler().Finish(RenderAll(bad), absl::InternalError("disk full"));
    const std::vector<nlohmann::json> posted = endpoint_.Await(2);
    ASSERT_EQ(posted.size(), 2u);
    EXPECT_EQ(posted[0]["job_id"], good);
    EXPECT_EQ(posted[0]["name"], "good");
    EXPECT_EQ(posted[0]["owner"], "alice");
    EXPECT_EQ(posted[0]["state"], "succeeded");
    EXPECT_EQ(posted[0]["error"], "");
    for (const char* time : {"submitted", "started", "finished"}) {
        const std::string t = posted[0][time];
        EXPECT_EQ(t.size(), 20u) << time << " " << t;  // 2026-11-29T02:41:00Z
        EXPECT_EQ(t.back(), 'Z') << t;
    }
    EXPECT_EQ(posted[1]["job_id"], bad);
    EXPECT_EQ(posted[1]["state"], "failed");
    EXPECT_NE(posted[1]["error"].get<std::string>().find("disk full"), std::string::npos);
}

TEST_F(JobNotifierTest, HangingEndpointDoesNotHoldUpTheJobsEnds) {
    endpoint_.Hang(true);
    const std::string first = Queue("first");
    ASSERT_TRUE(farm_->scheduler().Cancel(first).ok());
    endpoint_.Await(1);  // the notifier thread is now stuck in its POST
    const std::string second = Queue("second");
    farm_->scheduler().Finish(RenderAll(second), std::string("/results/second.exr"));
    EXPECT_EQ(farm_->scheduler().Get(second)->state, JobState::kSucceeded);
    const std::string third = Queue("third");
    ASSERT_TRUE(farm_->scheduler().Cancel(third).ok());
    EXPECT_EQ(farm_->scheduler().Get(third)->state, JobState::kCancelled);
    endpoint_.Hang(false);
    const std::vector<nlohmann::json> posted = endpoint_.Await(3);
    ASSERT_EQ(posted.size(), 3u);
    EXPECT_EQ(posted[0]["state"], "cancelled");
    EXPECT_EQ(posted[1]["job_id"], second);
    EXPECT_EQ(posted[2]["job_id"], third);
}

TEST(JobNotifier, QueueIsBoundedDroppingTheOldest) {
    Endpoint endpoint;
    endpoint.Hang(true);
    absl::StatusOr<std::unique_ptr<JobNotifier>> notifier =
        JobNotifier::Start(endpoint.url(), JobNotifierOptions{.max_queued = 2});
    ASSERT_TRUE(notifier.ok()) << notifier.status();
    JobRecord job;
    job.id = "a";
    (*notifier)->JobEnded(job);
    endpoint.Await(1);  // "a" is being posted: the queue is empty
    for (const char* id : {"b", "c", "d", "e"}) {
        job.id = id;
        (*notifier)->JobEnded(job);  // returns at once; "b" and "c" are dropped
    }
    endpoint.Hang(false);
    std::vector<std::string> ids;
    for (const nlohmann::json& body : endpoint.Await(3)) ids.push_back(body["job_id"]);
    EXPECT_EQ(ids, (std::vector<std::string>{"a", "d", "e"}));
}

// An endpoint that never answers, with an attempt's timeout of an hour: stopping the notifier
// (the coordinator's shutdown) aborts the attempt instead of waiting it out.
TEST(JobNotifier, StoppingAbortsTheAttemptUnderWay) {
    Endpoint endpoint;
    endpoint.Hang(true);
    absl::StatusOr<std::unique_ptr<JobNotifier>> notifier =
        JobNotifier::Start(endpoint.url(), JobNotifierOptions{.timeout = absl::Hours(1)});
    ASSERT_TRUE(notifier.ok()) << notifier.status();
    JobRecord job;
    job.id = "a";
    (*notifier)->JobEnded(job);
    endpoint.Await(1);  // the post is under way, its answer held
    std::future<void> stopped = std::async(std::launch::async, [&] { notifier->reset(); });
    // A bound for a broken test, not a timing: without the abort this waits an hour.
    EXPECT_EQ(stopped.wait_for(std::chrono::minutes(1)), std::future_status::ready);
    endpoint.Hang(false);
}

TEST(JobNotifier, BadUrlIsRefusedNamingTheFlag) {
    for (const char* url : {"ftp://host/x", "http://", "host:80/x", "http:///x", "http://a b/"}) {
        const absl::Status s = JobNotifier::Start(url).status();
        EXPECT_TRUE(absl::IsInvalidArgument(s)) << url;
        EXPECT_NE(s.message().find("--notify-url"), std::string::npos) << s;
    }
    EXPECT_TRUE(JobNotifier::Start("https://hooks.example.com:8443/lightfarm").ok());
}

}  // namespace
}  // namespace lf
