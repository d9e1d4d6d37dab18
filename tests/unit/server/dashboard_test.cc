// The dashboard's handlers against a real Farm in a temporary data folder, without a browser or
// a socket: signing in and being refused, what each token sees (another's job answers as no
// job), the JSON of jobs, tasks, workers and the farm, cancel and priority, the preview PNG
// (decoded, and changed by a merged task), the CSRF checks of POSTs, bounds on what a request
// names, anonymous admins only on loopback, and the embedded pages with their headers; a shot's
// frames with their states, paged, and each frame's preview and tasks; the jobs list filtered
// and paged, tasks by state and paged, delete, the EXR download, the graded preview.
#include "lf/server/dashboard.h"

#include <gtest/gtest.h>
#include <stb_image.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "absl/strings/match.h"
#include "absl/strings/str_split.h"
#include "lf/core/tile_codec.h"
#include "lf/server/web_assets.h"
#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

constexpr char kHost[] = "127.0.0.1:8080";
constexpr char kOrigin[] = "http://127.0.0.1:8080";

std::string HeaderOf(const HttpAnswer& a, const std::string& name) {
    for (const auto& [n, v] : a.headers) {
        if (n == name) return v;
    }
    return "";
}

class DashboardTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = testing::FreshTestDir("lf_dashboard");
        FarmOptions options;
        options.data_dir = dir_.string();
        absl::StatusOr<std::unique_ptr<Farm>> farm = Farm::Open(options);
        ASSERT_TRUE(farm.ok()) << farm.status();
        farm_ = std::move(*farm);
        absl::StatusOr<std::unique_ptr<TokenStore>> tokens = TokenStore::Open(dir_.string());
        absl::StatusOr<std::unique_ptr<TokenStore>> admin = TokenStore::Open(dir_.string());
        ASSERT_TRUE(tokens.ok() && admin.ok());
        alice_ = *(*admin)->Create("alice", Role::kSubmitter);
        bob_ = *(*admin)->Create("bob", Role::kSubmitter);
        root_ = *(*admin)->Create("root", Role::kAdmin);
        worker_ = *(*admin)->Create("node-1", Role::kWorker);
        auth_ = std::make_unique<Authenticator>(std::move(*tokens), false);
        dashboard_ = std::make_unique<Dashboard>(*farm_, *auth_, DashboardOptions{});
    }
    void TearDown() override {
        dashboard_.reset();
        farm_.reset();
        fs::remove_all(dir_);
    }

    // A 16x16 image in 8x8 tiles, 4 spp in 2 passes: 8 tasks.
    std::string Submit(const std::string& owner, const std::string& name = "") {
        JobSpec spec;
        spec.name = name.empty() ? "of " + owner : name;
        spec.owner = owner;
        spec.plan = {16, 16, 4, 8, 2};
        absl::StatusOr<std::string> id = farm_->scheduler().Submit(spec);
        EXPECT_TRUE(id.ok()) << id.status();
        return *id;
    }

    // A shot of `frames` at 16x16, one 8x8 tile a task in one pass of 2 spp: 4 tasks a frame,
    // `tile` 16 for one.
    std::string SubmitShot(const std::string& owner, FrameRange frames, int tile = 8) {
        JobSpec spec;
        spec.name = "shot of " + owner;
        spec.owner = owner;
        spec.plan = {16, 16, 2, tile, 1};
        spec.shot.frames = frames;
        absl::StatusOr<std::string> id = farm_->scheduler().Submit(spec);
        EXPECT_TRUE(id.ok()) << id.status();
        return *id;
    }

    // Leases a task and merges a result of `value` in every pixel through the Farm; false when
    // no task is queued.
    bool RenderOne(const std::string& worker, float value) {
        std::optional<TaskAssignment> lease = farm_->scheduler().LeaseTask(worker);
        return lease && Merge(*lease, worker, value);
    }
    bool Merge(const TaskAssignment& lease, const std::string& worker, float value,
               const TaskTimes& times = {}) {
        TileSums sums(lease.task.rect);
        for (PixelSums& p : sums.pixels) {
            for (uint64_t s = lease.task.sample_begin; s < lease.task.sample_end; ++s) {
                p.Add(s, Rgb(value));
            }
        }
        // A shot's task names its frame (a still's none).
        const absl::Status merged =
            farm_->Complete(lease.lease_id, worker, EncodeTileSums(sums), std::nullopt,
                            std::nullopt, lease.frame, {}, times);
        EXPECT_TRUE(merged.ok()) << merged;
        return merged.ok();
    }

    static HttpRequest Get(const std::string& path, const std::string& token = "") {
        HttpRequest r;
        r.path = path;
        const size_t q = path.find('?');
        if (q != std::string::npos) {
            r.path = path.substr(0, q);
            for (absl::string_view pair : absl::StrSplit(path.substr(q + 1), '&')) {
                std::pair<std::string, std::string> kv = absl::StrSplit(pair, '=');
                r.query.insert(kv);
            }
        }
        r.headers["host"] = kHost;
        r.remote_addr = "127.0.0.1";
        if (!token.empty()) r.headers["cookie"] = std::string("theme=dark; lf_token=") + token;
        return r;
    }
    static HttpRequest Post(const std::string& path, const Json& body,
                            const std::string& token = "") {
        HttpRequest r = Get(path, token);
        r.method = "POST";
        r.body = body.dump();
        r.headers["content-type"] = "application/json";
        r.headers["origin"] = kOrigin;
        return r;
    }

    // Serves the request, expecting `status`, and parses the JSON answer.
    Json Call(const HttpRequest& request, int status) {
        const HttpAnswer a = dashboard_->Serve(request);
        EXPECT_EQ(a.status, status) << request.method << " " << request.path << ": " << a.body;
        EXPECT_EQ(a.content_type, "application/json") << request.path;
        EXPECT_EQ(HeaderOf(a, "Cache-Control"), "no-store");
        return Json::parse(a.body, nullptr, false);
    }

    fs::path dir_;
    std::unique_ptr<Farm> farm_;
    std::unique_ptr<Authenticator> auth_;
    std::unique_ptr<Dashboard> dashboard_;
    std::string alice_, bob_, root_, worker_;
};

TEST_F(DashboardTest, UnauthenticatedWrongAndWorkerTokensAreRefused) {
    const Json none = Call(Get("/api/jobs"), 401);
    EXPECT_TRUE(none.contains("error"));
    Call(Get("/api/jobs", "lf1_" + std::string(64, '0')), 401);
    Call(Get("/api/session", "garbage"), 401);
    const Json worker = Call(Get("/api/jobs", worker_), 403);
    EXPECT_TRUE(absl::StrContains(worker["error"].get<std::string>(), "role worker"));
    HttpRequest bearer = Get("/api/session");
    bearer.headers["authorization"] = "Bearer " + alice_;
    const Json me = Call(bearer, 200);
    EXPECT_EQ(me["name"], "alice");
    EXPECT_EQ(me["role"], "submitter");
    EXPECT_EQ(me["auth"], true);
}

TEST_F(DashboardTest, SignInSetsAStrictHttpOnlyCookieOnlyForAValidToken) {
    const HttpAnswer ok = dashboard_->Serve(Post("/api/session", {{"token", alice_}}));
    ASSERT_EQ(ok.status, 200) << ok.body;
    const std::string cookie = HeaderOf(ok, "Set-Cookie");
    EXPECT_TRUE(absl::StartsWith(cookie, "lf_token=" + alice_ + ";")) << cookie;
    EXPECT_TRUE(absl::StrContains(cookie, "HttpOnly")) << cookie;
    EXPECT_TRUE(absl::StrContains(cookie, "SameSite=Strict")) << cookie;
    EXPECT_FALSE(absl::StrContains(cookie, "Secure")) << "plain HTTP: " << cookie;

    for (const std::string& bad : {std::string("lf1_nope"), worker_}) {
        const HttpAnswer refused = dashboard_->Serve(Post("/api/session", {{"token", bad}}));
        EXPECT_NE(refused.status, 200);
        EXPECT_EQ(HeaderOf(refused, "Set-Cookie"), "");
    }
    Call(Post("/api/session", {{"nothing", 1}}), 400);

    const HttpAnswer out = dashboard_->Serve(Post("/api/session/end", Json::object()));
    EXPECT_TRUE(absl::StrContains(HeaderOf(out, "Set-Cookie"), "Max-Age=0"));

    Dashboard over_tls(*farm_, *auth_, DashboardOptions{.tls = true});
    HttpRequest tls = Post("/api/session", {{"token", alice_}});
    tls.headers["origin"] = std::string("https://") + kHost;
    const HttpAnswer secure = over_tls.Serve(tls);
    ASSERT_EQ(secure.status, 200) << secure.body;
    EXPECT_TRUE(absl::StrContains(HeaderOf(secure, "Set-Cookie"), "; Secure"));
}

TEST_F(DashboardTest, PostsFromAnotherOriginOrNotJsonAreRefused) {
    const std::string job = Submit("alice");
    HttpRequest form = Post("/api/jobs/" + job + "/cancel", Json::object(), alice_);
    form.headers["content-type"] = "application/x-www-form-urlencoded";
    Call(form, 403);
    HttpRequest foreign = Post("/api/jobs/" + job + "/cancel", Json::object(), alice_);
    foreign.headers["origin"] = "http://evil.example";
    Call(foreign, 403);
    HttpRequest no_origin = Post("/api/jobs/" + job + "/cancel", Json::object(), alice_);
    no_origin.headers.erase("origin");
    Call(no_origin, 403);
    HttpRequest login = Post("/api/session", {{"token", alice_}});
    login.headers["origin"] = "http://evil.example";
    Call(login, 403);
    EXPECT_EQ(farm_->scheduler().Get(job)->state, JobState::kQueued);
    // A script's bearer token is not something a browser adds to a forged request.
    HttpRequest script = Post("/api/jobs/" + job + "/cancel", Json::object());
    script.headers.erase("origin");
    script.headers["authorization"] = "Bearer " + alice_;
    Call(script, 200);
    EXPECT_EQ(farm_->scheduler().Get(job)->state, JobState::kCancelled);
}

TEST_F(DashboardTest, SubmittersSeeOnlyTheirJobsAnotherAnswersAsNone) {
    const std::string mine = Submit("alice"), theirs = Submit("bob");
    const Json listed = Call(Get("/api/jobs", alice_), 200);
    ASSERT_EQ(listed["jobs"].size(), 1u);
    EXPECT_EQ(listed["jobs"][0]["id"], mine);
    EXPECT_EQ(Call(Get("/api/jobs", root_), 200)["jobs"].size(), 2u);

    const std::string unknown = "job-0000000000";
    for (const std::string what : {"", "/tasks", "/logs", "/preview.png", "/metadata"}) {
        const Json other = Call(Get("/api/jobs/" + theirs + what, alice_), 404);
        const Json none = Call(Get("/api/jobs/" + unknown + what, alice_), 404);
        EXPECT_EQ(other["error"], "no job " + theirs) << what;
        EXPECT_EQ(none["error"], "no job " + unknown) << what;
    }
    Call(Post("/api/jobs/" + theirs + "/cancel", Json::object(), alice_), 404);
    Call(Post("/api/jobs/" + theirs + "/priority", {{"priority", 9}}, alice_), 404);
    EXPECT_EQ(farm_->scheduler().Get(theirs)->state, JobState::kQueued);
    EXPECT_EQ(farm_->scheduler().Get(theirs)->spec.priority, 0);
    Call(Get("/api/jobs/" + theirs, root_), 200);

    // Workers busy with bob's job: alice sees that they are busy, not with what.
    farm_->scheduler().SetPriority(theirs, 5).IgnoreError();
    ASSERT_TRUE(farm_->scheduler().LeaseTask("w1"));
    const Json seen_by_alice = Call(Get("/api/workers", alice_), 200);
    ASSERT_EQ(seen_by_alice["workers"].size(), 1u);
    EXPECT_EQ(seen_by_alice["workers"][0]["state"], "busy");
    EXPECT_EQ(seen_by_alice["workers"][0]["job_id"], "(other)");
    EXPECT_EQ(Call(Get("/api/workers", root_), 200)["workers"][0]["job_id"], theirs);
    EXPECT_EQ(Call(Get("/api/workers", bob_), 200)["workers"][0]["job_id"], theirs);
}

TEST_F(DashboardTest, AuthOffEveryoneIsAnAnonymousAdmin) {
    std::unique_ptr<Authenticator> off = Authenticator::Off();
    Dashboard open(*farm_, *off, DashboardOptions{});
    const std::string job = Submit("");
    const HttpAnswer me = open.Serve(Get("/api/session"));
    ASSERT_EQ(me.status, 200);
    EXPECT_EQ(Json::parse(me.body)["role"], "admin");
    EXPECT_EQ(Json::parse(me.body)["auth"], false);
    const HttpAnswer jobs = open.Serve(Get("/api/jobs"));
    EXPECT_EQ(Json::parse(jobs.body)["jobs"][0]["id"], job);
    // Still no forged POST: a page on another site could reach a loopback server.
    HttpRequest forged = Post("/api/jobs/" + job + "/cancel", Json::object());
    forged.headers["origin"] = "http://evil.example";
    EXPECT_EQ(open.Serve(forged).status, 403);
    // Nor another machine, nor a page of another site renamed to 127.0.0.1 (DNS rebinding).
    HttpRequest remote = Get("/api/jobs");
    remote.remote_addr = "10.0.0.7";
    EXPECT_EQ(open.Serve(remote).status, 403);
    HttpRequest rebound = Get("/api/jobs");
    rebound.headers["host"] = "evil.example:8080";
    EXPECT_EQ(open.Serve(rebound).status, 403);
    HttpRequest named = Get("/api/jobs");
    named.headers["host"] = "localhost:8080";
    named.remote_addr = "::1";
    EXPECT_EQ(open.Serve(named).status, 200);
    EXPECT_EQ(farm_->scheduler().Get(job)->state, JobState::kQueued);
}

TEST_F(DashboardTest, JobTasksAndFarmJsonFollowTheWork) {
    const std::string job = Submit("alice");
    Json j = Call(Get("/api/jobs/" + job, alice_), 200);
    EXPECT_EQ(j["state"], "queued");
    EXPECT_EQ(j["owner"], "alice");
    EXPECT_EQ(j["tasks_total"], 8);
    EXPECT_EQ(j["tasks_done"], 0);
    EXPECT_TRUE(j["started_ms"].is_null());
    EXPECT_TRUE(j["eta_s"].is_null());
    EXPECT_EQ(j["width"], 16);

    ASSERT_TRUE(RenderOne("w1", 0.5f));
    ASSERT_TRUE(RenderOne("w1", 0.5f));
    j = Call(Get("/api/jobs/" + job, alice_), 200);
    EXPECT_EQ(j["state"], "running");
    EXPECT_EQ(j["tasks_done"], 2);
    EXPECT_TRUE(j["started_ms"].is_number());
    EXPECT_TRUE(j["eta_s"].is_number());
    EXPECT_GE(j["eta_s"].get<double>(), 0);

    const Json tasks = Call(Get("/api/jobs/" + job + "/tasks", alice_), 200)["tasks"];
    ASSERT_EQ(tasks.size(), 8u);
    int done = 0;
    for (const Json& t : tasks) {
        done += t["state"] == "done";
        EXPECT_EQ(t["width"], 8);
        if (t["state"] == "done") {
            EXPECT_EQ(t["worker"], "w1");
        }
    }
    EXPECT_EQ(done, 2);
    const Json logs = Call(Get("/api/jobs/" + job + "/logs?task=0&after=0", alice_), 200);
    EXPECT_TRUE(logs["lines"].is_array());

    const Json farm = Call(Get("/api/farm", alice_), 200);
    EXPECT_EQ(farm["queue_depth"], 6);
    EXPECT_EQ(farm["jobs_running"], 1);
    ASSERT_EQ(farm["tasks_per_minute"].size(), size_t(MinuteCounts::kMinutes));
    // Both merged within the last minute or two (the minute may have turned between them).
    const Json& per_minute = farm["tasks_per_minute"];
    EXPECT_EQ(per_minute[58].get<int>() + per_minute[59].get<int>(), 2);
    // 2 tasks of 8x8 pixels and 2 of the 4 samples each.
    EXPECT_EQ(farm["samples_per_minute"][58].get<int>() + farm["samples_per_minute"][59].get<int>(),
              2 * 8 * 8 * 2);
}

// Dependencies (issue 30): the job page's JSON names each job it runs after with its state now.
TEST_F(DashboardTest, AJobListsItsDependenciesWithTheirStates) {
    const std::string first = Submit("alice"), second = Submit("alice");
    EXPECT_FALSE(Call(Get("/api/jobs/" + second, alice_), 200).contains("depends_on"));
    ASSERT_TRUE(farm_->scheduler().AddDependencies(second, {first}).ok());
    Json j = Call(Get("/api/jobs/" + second, alice_), 200);
    EXPECT_EQ(j["depends_on"], Json::parse(R"([{"id": ")" + first + R"(", "state": "queued"}])"));
    ASSERT_TRUE(farm_->scheduler().Cancel(first).ok());
    j = Call(Get("/api/jobs/" + second, alice_), 200);
    EXPECT_EQ(j["depends_on"][0]["state"], "cancelled");
    EXPECT_EQ(j["state"], "failed");
    EXPECT_EQ(j["error"], "dependency " + first + " was cancelled");
}

TEST_F(DashboardTest, CancelAndPriorityChangeTheJob) {
    const std::string first = Submit("alice"), second = Submit("alice");
    Json j = Call(Post("/api/jobs/" + second + "/priority", {{"priority", 7}}, alice_), 200);
    EXPECT_EQ(j["priority"], 7);
    EXPECT_EQ(farm_->scheduler().Get(second)->spec.priority, 7);
    EXPECT_EQ(farm_->scheduler().LeaseTask("w")->job_id, second);
    for (const Json& bad : {Json{{"priority", "high"}}, Json{{"priority", 1.5}},
                            Json{{"priority", int64_t(1) << 40}}, Json::object()}) {
        Call(Post("/api/jobs/" + second + "/priority", bad, alice_), 400);
    }
    j = Call(Post("/api/jobs/" + first + "/cancel", Json::object(), alice_), 200);
    EXPECT_EQ(j["state"], "cancelled");
    EXPECT_EQ(farm_->scheduler().Get(first)->state, JobState::kCancelled);
    Call(Post("/api/jobs/" + first + "/cancel", Json::object(), alice_), 409);
    Call(Post("/api/jobs/" + first + "/priority", {{"priority", 1}}, alice_), 409);
}

TEST_F(DashboardTest, PreviewIsAPngThatChangesWhenATaskMerges) {
    dashboard_ = std::make_unique<Dashboard>(
        *farm_, *auth_, DashboardOptions{.preview_min_age = absl::ZeroDuration()});
    const std::string job = Submit("alice");
    ASSERT_TRUE(RenderOne("w1", 0.5f));
    const std::string path = "/api/jobs/" + job + "/preview.png";
    const HttpAnswer first = dashboard_->Serve(Get(path, alice_));
    ASSERT_EQ(first.status, 200) << first.body;
    EXPECT_EQ(first.content_type, "image/png");
    auto decode = [](const std::string& png) {
        int w = 0, h = 0, channels = 0;
        unsigned char* data =
            stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png.data()),
                                  int(png.size()), &w, &h, &channels, 3);
        EXPECT_NE(data, nullptr);
        EXPECT_EQ(w, 16);
        EXPECT_EQ(h, 16);
        std::vector<unsigned char> rgb;
        if (data) rgb.assign(data, data + size_t(w) * h * 3);
        stbi_image_free(data);
        return rgb;
    };
    const std::vector<unsigned char> before = decode(first.body);
    const std::string etag = HeaderOf(first, "ETag");
    ASSERT_FALSE(etag.empty());
    HttpRequest again = Get(path, alice_);
    again.headers["if-none-match"] = etag;
    EXPECT_EQ(dashboard_->Serve(again).status, 304);

    ASSERT_TRUE(RenderOne("w1", 0.9f));
    const HttpAnswer second = dashboard_->Serve(again);  // the old ETag
    ASSERT_EQ(second.status, 200);
    EXPECT_NE(HeaderOf(second, "ETag"), etag);
    const std::vector<unsigned char> after = decode(second.body);
    ASSERT_EQ(after.size(), before.size());
    EXPECT_NE(after, before);
    // The tile's second pass (0.9) brightened its first (0.5); the other tiles stay black.
    size_t brighter = 0, black = 0;
    for (size_t i = 0; i < after.size(); ++i) {
        brighter += before[i] > 0 && after[i] > before[i];
        black += before[i] == 0 && after[i] == 0;
    }
    EXPECT_EQ(brighter, size_t(8 * 8 * 3));
    EXPECT_EQ(black, size_t(3 * 8 * 8 * 3));

    const Json metadata = Call(Get("/api/jobs/" + job + "/metadata", alice_), 200);
    EXPECT_EQ(metadata["attributes"]["lightfarm.spp"], 4);
    EXPECT_TRUE(metadata["attributes"]["lightfarm.method"].is_string());
}

// Many tabs on a job whose tasks merge fast cost one preview per preview_min_age.
TEST_F(DashboardTest, ARunningJobsPreviewIsMadeAtMostOncePerMinimumAge) {
    dashboard_ = std::make_unique<Dashboard>(*farm_, *auth_,
                                             DashboardOptions{.preview_min_age = absl::Hours(1)});
    const std::string job = Submit("alice");
    ASSERT_TRUE(RenderOne("w1", 0.5f));
    const std::string path = "/api/jobs/" + job + "/preview.png";
    const HttpAnswer first = dashboard_->Serve(Get(path, alice_));
    ASSERT_EQ(first.status, 200);
    ASSERT_TRUE(RenderOne("w1", 0.9f));
    const HttpAnswer soon = dashboard_->Serve(Get(path, alice_));
    EXPECT_EQ(soon.body, first.body);
    EXPECT_EQ(HeaderOf(soon, "ETag"), HeaderOf(first, "ETag"));
    // Ended, it is made again at once: the last tasks are never left out.
    while (RenderOne("w1", 0.9f)) {
    }
    ASSERT_EQ(farm_->scheduler().Get(job)->state, JobState::kSucceeded);
    const HttpAnswer final = dashboard_->Serve(Get(path, alice_));
    ASSERT_EQ(final.status, 200);
    EXPECT_NE(final.body, first.body);
}

// The PNG's size and RGB bytes.
struct Decoded {
    int width = 0, height = 0;
    std::vector<unsigned char> rgb;
};
Decoded DecodePng(const std::string& png) {
    Decoded d;
    int channels = 0;
    unsigned char* data = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(png.data()),
                                                int(png.size()), &d.width, &d.height, &channels, 3);
    EXPECT_NE(data, nullptr);
    if (data) d.rgb.assign(data, data + size_t(d.width) * d.height * 3);
    stbi_image_free(data);
    return d;
}

TEST_F(DashboardTest, AShotsJobListsItsFramesWithTheirStates) {
    const std::string job = SubmitShot("alice", {1, 3, 1});
    Json j = Call(Get("/api/jobs/" + job, alice_), 200);
    EXPECT_EQ(j["shot"]["frames_total"], 3);
    EXPECT_EQ(j["shot"]["frames_done"], 0);
    EXPECT_EQ(j["shot"]["current"], 1);
    EXPECT_EQ(j["shot"]["fps"], 24.0);
    ASSERT_EQ(j["frames"].size(), 3u);
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(j["frames"][i]["frame"], i + 1);
        EXPECT_EQ(j["frames"][i]["state"], "queued");
        EXPECT_TRUE(j["frames"][i]["preview"].is_null());
    }

    // Frame 1's first task leased: rendering, though nothing of it merged yet.
    std::optional<TaskAssignment> lease = farm_->scheduler().LeaseTask("w1");
    ASSERT_TRUE(lease && lease->frame == 1);
    j = Call(Get("/api/jobs/" + job, alice_), 200);
    EXPECT_EQ(j["frames"][0]["state"], "rendering");
    EXPECT_TRUE(j["frames"][0]["preview"].is_null());
    EXPECT_EQ(j["frames"][1]["state"], "queued");
    ASSERT_TRUE(Merge(*lease, "w1", 0.5f));

    for (int t = 0; t < 4; ++t) ASSERT_TRUE(RenderOne("w1", 0.5f));  // frame 1 and a task of 2
    j = Call(Get("/api/jobs/" + job, alice_), 200);
    EXPECT_EQ(j["shot"]["frames_done"], 1);
    EXPECT_EQ(j["shot"]["current"], 2);
    EXPECT_EQ(j["frames"][0]["state"], "done");
    EXPECT_EQ(j["frames"][0]["tasks_done"], 4);
    EXPECT_EQ(j["frames"][0]["tasks_total"], 4);
    EXPECT_EQ(j["frames"][0]["preview"], "/api/jobs/" + job + "/frames/1/preview.png?v=4-done");
    EXPECT_EQ(j["frames"][1]["state"], "rendering");
    EXPECT_EQ(j["frames"][1]["tasks_done"], 1);
    EXPECT_EQ(j["frames"][1]["preview"], "/api/jobs/" + job + "/frames/2/preview.png?v=1");
    EXPECT_EQ(j["frames"][2]["state"], "queued");

    // The list shows how far the shot is, not its frames.
    const Json listed = Call(Get("/api/jobs", alice_), 200)["jobs"][0];
    EXPECT_EQ(listed["shot"]["frames_done"], 1);
    EXPECT_FALSE(listed.contains("frames"));

    // Cancelled: the finished frame stays done with its preview, the others say why they never
    // will be.
    Call(Post("/api/jobs/" + job + "/cancel", Json::object(), alice_), 200);
    j = Call(Get("/api/jobs/" + job, alice_), 200);
    EXPECT_EQ(j["frames"][0]["state"], "done");
    EXPECT_FALSE(j["frames"][0]["preview"].is_null());
    EXPECT_EQ(j["frames"][1]["state"], "cancelled");
    EXPECT_TRUE(j["frames"][1]["preview"].is_null());
    EXPECT_EQ(j["frames"][2]["state"], "cancelled");
    const HttpAnswer kept =
        dashboard_->Serve(Get("/api/jobs/" + job + "/frames/1/preview.png", alice_));
    EXPECT_EQ(kept.status, 200) << kept.body;
    // An ended shot's tasks, as recorded when it ended, still name their frames.
    const Json tasks = Call(Get("/api/jobs/" + job + "/tasks?frame=1", alice_), 200)["tasks"];
    ASSERT_EQ(tasks.size(), 4u);
    for (const Json& t : tasks) EXPECT_EQ(t["state"], "done");
}

// History (issue 30): the workers' times of a job, its frames and its tasks, kept by the store
// across a coordinator restart, and its history (lf::FarmStats) after the job is deleted.
TEST_F(DashboardTest, JobFramesAndTasksShowTheirWorkersTimesAcrossARestart) {
    const std::string job = SubmitShot("alice", {1, 2, 1}, 16);  // one task a frame
    for (const TaskTimes& times : {TaskTimes{2, 3}, TaskTimes{4, 7}}) {
        std::optional<TaskAssignment> lease = farm_->scheduler().LeaseTask("w1");
        ASSERT_TRUE(lease);
        ASSERT_TRUE(Merge(*lease, "w1", 0.5f, times));
    }
    const auto expect_times = [&](const std::string& token) {
        const Json j = Call(Get("/api/jobs/" + job, token), 200);
        EXPECT_EQ(j["state"], "succeeded");
        EXPECT_EQ(j["render_s"], 6.0);
        EXPECT_EQ(j["cpu_s"], 10.0);
        ASSERT_EQ(j["frames"].size(), 2u);
        EXPECT_EQ(j["frames"][0]["render_s"], 2.0);
        EXPECT_EQ(j["frames"][0]["cpu_s"], 3.0);
        EXPECT_EQ(j["frames"][1]["render_s"], 4.0);
        EXPECT_EQ(j["frames"][1]["cpu_s"], 7.0);
        const Json tasks = Call(Get("/api/jobs/" + job + "/tasks", token), 200)["tasks"];
        ASSERT_EQ(tasks.size(), 2u);
        EXPECT_EQ(tasks[0]["cpu_s"], 3.0);
        EXPECT_EQ(tasks[1]["cpu_s"], 7.0);
    };
    expect_times(alice_);

    dashboard_.reset();
    farm_.reset();
    FarmOptions options;
    options.data_dir = dir_.string();
    absl::StatusOr<std::unique_ptr<Farm>> again = Farm::Open(options);
    ASSERT_TRUE(again.ok()) << again.status();
    farm_ = std::move(*again);
    dashboard_ = std::make_unique<Dashboard>(*farm_, *auth_, DashboardOptions{});
    expect_times(alice_);

    ASSERT_TRUE(farm_->DeleteJob(job).ok());
    const absl::StatusOr<FarmStats> stats = farm_->store().Stats({});
    ASSERT_TRUE(stats.ok()) << stats.status();
    ASSERT_EQ(stats->owners.size(), 1u);
    EXPECT_EQ(stats->owners[0], (OwnerStats{"alice", 1, 0, 0, 0, 2, 2 * 16 * 16 * 2, {6, 10}}));
    ASSERT_EQ(stats->workers.size(), 1u);
    EXPECT_EQ(stats->workers[0], (WorkerStats{"w1", 2, 0, {6, 10}}));
}

TEST_F(DashboardTest, AStillHasNoFrames) {
    const std::string job = Submit("alice");
    const Json j = Call(Get("/api/jobs/" + job, alice_), 200);
    EXPECT_TRUE(j["shot"].is_null());
    EXPECT_FALSE(j.contains("frames"));
    const Json refused = Call(Get("/api/jobs/" + job + "/frames/1/preview.png", alice_), 404);
    EXPECT_EQ(refused["error"], "job " + job + " renders no frame 1 (a still)");
    Call(Get("/api/jobs/" + job + "/tasks?frame=1", alice_), 404);
}

TEST_F(DashboardTest, AFramesPreviewIsAPngOfTheFramesSizeAndAnUnknownFrameIsNamed) {
    dashboard_ = std::make_unique<Dashboard>(
        *farm_, *auth_, DashboardOptions{.preview_min_age = absl::ZeroDuration()});
    const std::string job = SubmitShot("alice", {10, 14, 2});        // frames 10, 12, 14
    for (int t = 0; t < 4; ++t) ASSERT_TRUE(RenderOne("w1", 0.2f));  // frame 10
    ASSERT_TRUE(RenderOne("w1", 0.8f));                              // a tile of frame 12
    const std::string ten = "/api/jobs/" + job + "/frames/10/preview.png";
    const std::string twelve = "/api/jobs/" + job + "/frames/12/preview.png";
    const HttpAnswer done = dashboard_->Serve(Get(ten, alice_));
    ASSERT_EQ(done.status, 200) << done.body;
    EXPECT_EQ(done.content_type, "image/png");
    const Decoded d = DecodePng(done.body);
    EXPECT_EQ(d.width, 16);
    EXPECT_EQ(d.height, 16);
    // Every pixel of the finished frame alike, and lit.
    ASSERT_FALSE(d.rgb.empty());
    EXPECT_GT(d.rgb[0], 0);
    EXPECT_EQ(std::count(d.rgb.begin(), d.rgb.end(), d.rgb[0]), std::ptrdiff_t(d.rgb.size()));
    // A finished frame held by the browser is not encoded again.
    HttpRequest again = Get(ten, alice_);
    again.headers["if-none-match"] = HeaderOf(done, "ETag");
    EXPECT_EQ(dashboard_->Serve(again).status, 304);

    // The rendering frame: its one merged tile (brighter than frame 10), the rest black.
    const HttpAnswer rendering = dashboard_->Serve(Get(twelve, alice_));
    ASSERT_EQ(rendering.status, 200) << rendering.body;
    const Decoded r = DecodePng(rendering.body);
    EXPECT_EQ(r.width, 16);
    EXPECT_EQ(r.height, 16);
    EXPECT_EQ(std::count(r.rgb.begin(), r.rgb.end(), 0), std::ptrdiff_t(3 * 8 * 8 * 3));
    EXPECT_EQ(*std::max_element(r.rgb.begin(), r.rgb.end()) > d.rgb[0], true);
    EXPECT_NE(HeaderOf(rendering, "ETag"), HeaderOf(done, "ETag"));

    const Json metadata = Call(Get("/api/jobs/" + job + "/frames/10/metadata", alice_), 200);
    EXPECT_EQ(metadata["attributes"]["lightfarm.frame"], 10);

    const Json tasks = Call(Get("/api/jobs/" + job + "/tasks?frame=12", alice_), 200)["tasks"];
    ASSERT_EQ(tasks.size(), 4u);
    int merged = 0;
    for (const Json& t : tasks) {
        merged += t["state"] == "done";
        EXPECT_EQ(t["frames"], Json::array({12}));
    }
    EXPECT_EQ(merged, 1);

    for (const std::string what : {"/frames/11/preview.png", "/frames/16/metadata"}) {
        const Json unknown = Call(Get("/api/jobs/" + job + what, alice_), 404);
        const std::string error = unknown["error"];
        EXPECT_TRUE(absl::StrContains(error, "no frame 1")) << error;
        EXPECT_TRUE(absl::StrContains(error, job)) << error;
        EXPECT_TRUE(absl::StrContains(error, "(its frames: 10-14:2)")) << error;
    }
    EXPECT_EQ(Call(Get("/api/jobs/" + job + "/tasks?frame=13", alice_), 404)["error"],
              "job " + job + " renders no frame 13 (its frames: 10-14:2)");
    Call(Get("/api/jobs/" + job + "/frames/ten/preview.png", alice_), 404);
    Call(Get("/api/jobs/" + job + "/frames/10/tasks", alice_), 404);
    // Another's shot's frame answers as no job.
    EXPECT_EQ(Call(Get(ten, bob_), 404)["error"], "no job " + job);
}

// 10000 frames: one answer lists kFramesListed of them, from the current frame's page or the
// one asked for, and says how many there are.
TEST_F(DashboardTest, ALongShotsFramesComeInPages) {
    const std::string job = SubmitShot("alice", {1, 10000, 1}, 16);
    const std::string path = "/api/jobs/" + job;
    Json j = Call(Get(path, alice_), 200);
    EXPECT_EQ(j["shot"]["frames_total"], 10000);
    EXPECT_EQ(j["shot"]["frames_from"], 0);
    EXPECT_EQ(j["shot"]["frames_per_page"], Dashboard::kFramesListed);
    ASSERT_EQ(j["frames"].size(), size_t(Dashboard::kFramesListed));
    EXPECT_EQ(j["frames"][0]["frame"], 1);
    j = Call(Get(path + "?frames_from=9950", alice_), 200);
    EXPECT_EQ(j["shot"]["frames_from"], 9950);
    ASSERT_EQ(j["frames"].size(), 50u);
    EXPECT_EQ(j["frames"][49]["frame"], 10000);
    Call(Get(path + "?frames_from=10000", alice_), 400);
    Call(Get(path + "?frames_from=-1", alice_), 400);
    // The whole answer stays small: 100 frames, not 10000.
    EXPECT_LT(dashboard_->Serve(Get(path, alice_)).body.size(), 20000u);

    // Unasked, the page is the current frame's (frames merge slowly in so long a record: a
    // shorter shot past its first page shows it).
    Call(Post(path + "/cancel", Json::object(), alice_), 200);
    const std::string shorter = SubmitShot("alice", {1, 150, 1}, 16);
    for (int t = 0; t < Dashboard::kFramesListed + 5; ++t) ASSERT_TRUE(RenderOne("w1", 0.5f));
    j = Call(Get("/api/jobs/" + shorter, alice_), 200);
    EXPECT_EQ(j["shot"]["current"], Dashboard::kFramesListed + 6);
    EXPECT_EQ(j["shot"]["frames_from"], Dashboard::kFramesListed);
    ASSERT_EQ(j["frames"].size(), size_t(150 - Dashboard::kFramesListed));
    EXPECT_EQ(j["frames"][0]["frame"], Dashboard::kFramesListed + 1);
    EXPECT_EQ(j["frames"][4]["state"], "done");
    EXPECT_EQ(j["frames"][5]["state"], "queued");
}

TEST_F(DashboardTest, WhatARequestNamesIsBounded) {
    Submit("alice");
    Call(Get("/api/jobs?limit=0", alice_), 400);
    Call(Get("/api/jobs?limit=100000", alice_), 400);
    Call(Get("/api/jobs?limit=abc", alice_), 400);
    Call(Get("/api/jobs?limit=1", alice_), 200);
    Call(Get("/api/jobs?before=-1", alice_), 400);
    Call(Get("/api/jobs/" + std::string(10000, 'a'), alice_), 404);
    Call(Get("/api/jobs/job-1%2F..%2Fx/tasks", alice_), 404);
    Call(Get("/api/jobs/a/b/c/d", alice_), 404);
    const std::string job = Submit("alice");
    Call(Get("/api/jobs/" + job + "/logs?max=100000", alice_), 400);
    Call(Get("/api/jobs/" + job + "/logs?task=-2", alice_), 400);
    Call(Get("/api/nothing", alice_), 404);
    HttpRequest put = Get("/api/jobs", alice_);
    put.method = "PUT";
    EXPECT_EQ(dashboard_->Serve(put).status, 405);
}

TEST_F(DashboardTest, PagesAreEmbeddedWithTheirTypesAndAStrictPolicy) {
    const HttpAnswer index = dashboard_->Serve(Get("/"));
    ASSERT_EQ(index.status, 200);
    EXPECT_EQ(index.content_type, "text/html; charset=utf-8");
    EXPECT_TRUE(absl::StrContains(index.body, "/web/app.js"));
    const std::string policy = HeaderOf(index, "Content-Security-Policy");
    EXPECT_TRUE(absl::StrContains(policy, "default-src 'none'")) << policy;
    EXPECT_TRUE(absl::StrContains(policy, "script-src 'self'")) << policy;
    EXPECT_FALSE(absl::StrContains(policy, "unsafe")) << policy;
    EXPECT_EQ(HeaderOf(index, "X-Content-Type-Options"), "nosniff");

    const HttpAnswer script = dashboard_->Serve(Get("/web/app.js"));
    ASSERT_EQ(script.status, 200);
    EXPECT_EQ(script.content_type, "text/javascript; charset=utf-8");
    HttpRequest cached = Get("/web/app.js");
    cached.headers["if-none-match"] = HeaderOf(script, "ETag");
    EXPECT_EQ(dashboard_->Serve(cached).status, 304);
    EXPECT_EQ(dashboard_->Serve(Get("/web/style.css")).content_type, "text/css; charset=utf-8");
    EXPECT_EQ(dashboard_->Serve(Get("/web/nothing.js")).status, 404);
    EXPECT_EQ(dashboard_->Serve(Get("/web/../farm.cc")).status, 404);
    // No page names anything beyond this server.
    for (const WebAsset& asset : WebAssets()) {
        const std::string content(asset.content);  // Debian's absl takes no std::string_view
        EXPECT_FALSE(absl::StrContains(content, "https://")) << asset.name;
        EXPECT_FALSE(absl::StrContains(content, "//cdn")) << asset.name;
    }
}

std::vector<std::string> IdsOf(const Json& answer) {
    std::vector<std::string> ids;
    for (const Json& j : answer["jobs"]) ids.push_back(j["id"]);
    return ids;
}

TEST_F(DashboardTest, JobsFilterByStateOwnerAndNameAndComeInPages) {
    const std::string a1 = Submit("alice", "Alpha one"), a2 = Submit("alice", "beta two");
    const std::string a3 = Submit("alice", "alpha three"), b1 = Submit("bob", "alpha of bob");
    ASSERT_TRUE(farm_->scheduler().Cancel(a2).ok());

    EXPECT_EQ(IdsOf(Call(Get("/api/jobs?state=cancelled", alice_), 200)),
              std::vector<std::string>{a2});
    EXPECT_EQ(IdsOf(Call(Get("/api/jobs?state=queued", alice_), 200)),
              (std::vector<std::string>{a3, a1}));
    // The name's substring, whatever its case; an id's too.
    EXPECT_EQ(IdsOf(Call(Get("/api/jobs?name=ALPHA", alice_), 200)),
              (std::vector<std::string>{a3, a1}));
    EXPECT_EQ(IdsOf(Call(Get("/api/jobs?name=" + a2, alice_), 200)), std::vector<std::string>{a2});
    EXPECT_EQ(IdsOf(Call(Get("/api/jobs?name=alpha", root_), 200)),
              (std::vector<std::string>{b1, a3, a1}));
    EXPECT_EQ(IdsOf(Call(Get("/api/jobs?owner=bob", root_), 200)), std::vector<std::string>{b1});
    // A submitter asking for another owner's jobs sees none.
    EXPECT_TRUE(Call(Get("/api/jobs?owner=bob", alice_), 200)["jobs"].empty());
    EXPECT_EQ(IdsOf(Call(Get("/api/jobs?owner=alice", alice_), 200)).size(), 3u);

    // Pages of 2 of the 3 queued: the second goes on from `next_before`, and is the last.
    const Json first = Call(Get("/api/jobs?state=queued&limit=1", root_), 200);
    EXPECT_EQ(IdsOf(first), std::vector<std::string>{b1});
    ASSERT_TRUE(first["next_before"].is_number());
    const Json second = Call(
        Get("/api/jobs?state=queued&limit=2&before=" + first["next_before"].dump(), root_), 200);
    EXPECT_EQ(IdsOf(second), (std::vector<std::string>{a3, a1}));
    const Json last = Call(
        Get("/api/jobs?state=queued&limit=2&before=" + second["next_before"].dump(), root_), 200);
    EXPECT_TRUE(last["jobs"].empty());
    EXPECT_TRUE(last["next_before"].is_null());
    EXPECT_TRUE(Call(Get("/api/jobs?limit=50", root_), 200)["next_before"].is_null());

    const Json bad_state = Call(Get("/api/jobs?state=sleeping", alice_), 400);
    EXPECT_TRUE(absl::StartsWith(bad_state["error"].get<std::string>(), "state: ")) << bad_state;
    const Json long_name = Call(Get("/api/jobs?name=" + std::string(300, 'x'), alice_), 400);
    EXPECT_TRUE(absl::StartsWith(long_name["error"].get<std::string>(), "name: ")) << long_name;
}

TEST_F(DashboardTest, TasksFilterByStateAndComeInPages) {
    const std::string job = Submit("alice");  // 8 tasks
    ASSERT_TRUE(RenderOne("w1", 0.5f));
    ASSERT_TRUE(farm_->scheduler().LeaseTask("w2"));
    const std::string path = "/api/jobs/" + job + "/tasks";
    const Json running = Call(Get(path + "?state=running", alice_), 200);
    ASSERT_EQ(running["tasks"].size(), 1u);
    EXPECT_EQ(running["tasks"][0]["worker"], "w2");
    EXPECT_EQ(running["total"], 1);
    EXPECT_EQ(Call(Get(path + "?state=done", alice_), 200)["tasks"][0]["worker"], "w1");
    const Json all = Call(Get(path, alice_), 200);
    EXPECT_EQ(all["tasks"].size(), 8u);
    EXPECT_EQ(all["counts"]["queued"], 6);
    EXPECT_EQ(all["counts"]["running"], 1);
    EXPECT_EQ(all["counts"]["done"], 1);

    const Json page = Call(Get(path + "?offset=3&limit=3", alice_), 200);
    ASSERT_EQ(page["tasks"].size(), 3u);
    EXPECT_EQ(page["tasks"][0]["index"], all["tasks"][3]["index"]);
    EXPECT_EQ(page["total"], 8);
    EXPECT_EQ(Call(Get(path + "?offset=6&limit=3", alice_), 200)["tasks"].size(), 2u);

    const Json bad = Call(Get(path + "?state=sleeping", alice_), 400);
    EXPECT_TRUE(absl::StrContains(bad["error"].get<std::string>(), "state: "));
    EXPECT_TRUE(absl::StrContains(bad["error"].get<std::string>(), "queued")) << bad;
    EXPECT_TRUE(absl::StartsWith(
        Call(Get(path + "?limit=0", alice_), 400)["error"].get<std::string>(), "limit: "));
    Call(Get(path + "?limit=100000", alice_), 400);
    EXPECT_TRUE(absl::StartsWith(
        Call(Get(path + "?offset=-1", alice_), 400)["error"].get<std::string>(), "offset: "));
}

TEST_F(DashboardTest, DeleteRemovesAnEndedJobOfItsOwnerOrForAnAdmin) {
    const std::string mine = Submit("alice"), theirs = Submit("bob");
    Call(Post("/api/jobs/" + mine + "/delete", Json::object(), alice_), 409);  // not ended
    ASSERT_TRUE(farm_->scheduler().Cancel(mine).ok());
    ASSERT_TRUE(farm_->scheduler().Cancel(theirs).ok());
    Call(Post("/api/jobs/" + theirs + "/delete", Json::object(), alice_), 404);
    EXPECT_TRUE(farm_->scheduler().Get(theirs).ok());
    EXPECT_EQ(Call(Post("/api/jobs/" + mine + "/delete", Json::object(), alice_), 200)["deleted"],
              mine);
    EXPECT_TRUE(absl::IsNotFound(farm_->scheduler().Get(mine).status()));
    Call(Get("/api/jobs/" + mine, alice_), 404);
    Call(Post("/api/jobs/" + theirs + "/delete", Json::object(), root_), 200);
    EXPECT_TRUE(absl::IsNotFound(farm_->scheduler().Get(theirs).status()));
    // The page's GET cannot delete.
    Call(Get("/api/jobs/" + mine + "/delete", alice_), 404);
}

// The jobs page's pause, resume and requeue, as JobService's: the owner or an admin; the
// workers page's disable, enable and drain, as SetWorkerState: admins only.
TEST_F(DashboardTest, JobAndWorkerActionsFollowTheRoles) {
    const std::string mine = Submit("alice");
    Call(Post("/api/jobs/" + mine + "/pause", Json::object(), bob_), 404);
    EXPECT_EQ(Call(Post("/api/jobs/" + mine + "/pause", Json::object(), alice_), 200)["paused"],
              true);
    EXPECT_TRUE(farm_->scheduler().Get(mine)->paused);
    EXPECT_FALSE(RenderOne("w1", 0.5f)) << "a paused job leases nothing";
    EXPECT_EQ(Call(Post("/api/jobs/" + mine + "/resume", Json::object(), root_), 200)["paused"],
              false);
    ASSERT_TRUE(farm_->scheduler().Cancel(mine).ok());
    Call(Post("/api/jobs/" + mine + "/pause", Json::object(), alice_), 409);  // ended
    EXPECT_EQ(Call(Post("/api/jobs/" + mine + "/requeue", Json::object(), alice_), 200)["state"],
              "queued");
    EXPECT_EQ(farm_->scheduler().Get(mine)->state, JobState::kQueued);

    ASSERT_TRUE(RenderOne("w1", 0.5f));  // w1 is known to the farm now
    Call(Post("/api/workers/w1/disable", Json::object(), alice_), 403);
    Call(Post("/api/workers/nobody/disable", Json::object(), root_), 404);
    Call(Post("/api/workers/w1/sleep", Json::object(), root_), 404);
    Call(Post("/api/workers//disable", Json::object(), root_), 404);
    const Json disabled = Call(Post("/api/workers/w1/disable", Json::object(), root_), 200);
    ASSERT_EQ(disabled["workers"].size(), 1u) << disabled;
    EXPECT_EQ(disabled["workers"][0]["state"], "disabled");
    EXPECT_FALSE(RenderOne("w1", 0.5f)) << "a disabled worker leases nothing";
    EXPECT_EQ(
        Call(Post("/api/workers/w1/enable", Json::object(), root_), 200)["workers"][0]["state"],
        "idle");
    EXPECT_TRUE(RenderOne("w1", 0.5f));
}

TEST_F(DashboardTest, TheResultExrIsAnAttachmentStreamedFromItsFile) {
    const std::string job = Submit("alice");
    Call(Get("/api/jobs/" + job + "/result.exr", alice_), 409);  // not rendered yet
    while (RenderOne("w1", 0.5f)) {
    }
    ASSERT_EQ(farm_->scheduler().Get(job)->state, JobState::kSucceeded);
    Call(Get("/api/jobs/" + job + "/result.exr", bob_), 404);
    const HttpAnswer a = dashboard_->Serve(Get("/api/jobs/" + job + "/result.exr", alice_));
    ASSERT_EQ(a.status, 200) << a.body;
    EXPECT_EQ(a.content_type, "image/x-exr");
    EXPECT_EQ(HeaderOf(a, "Content-Disposition"), "attachment; filename=\"" + job + ".exr\"");
    EXPECT_TRUE(a.body.empty()) << "the file is streamed, not copied into the answer";
    std::ifstream in(a.file, std::ios::binary);
    char magic[4] = {};
    ASSERT_TRUE(in.read(magic, 4)) << a.file;
    EXPECT_EQ(std::string(magic, 4), std::string("\x76\x2f\x31\x01", 4));
}

TEST_F(DashboardTest, ThePreviewIsGradedByExposureAndChannelFromTheLinearImage) {
    const std::string job = Submit("alice");
    ASSERT_TRUE(RenderOne("w1", 0.1f));
    const std::string path = "/api/jobs/" + job + "/preview.png";
    auto first_pixel = [&](const std::string& query) {
        const HttpAnswer a = dashboard_->Serve(Get(path + query, alice_));
        EXPECT_EQ(a.status, 200) << query << ": " << a.body;
        int w = 0, h = 0, n = 0;
        unsigned char* data =
            stbi_load_from_memory(reinterpret_cast<const unsigned char*>(a.body.data()),
                                  int(a.body.size()), &w, &h, &n, 3);
        EXPECT_NE(data, nullptr) << query;
        const int red = data ? data[0] : -1;
        stbi_image_free(data);
        return red;
    };
    const int plain = first_pixel("?exposure=0");
    EXPECT_GT(plain, 0);
    EXPECT_GT(first_pixel("?exposure=2"), plain);
    EXPECT_LT(first_pixel("?exposure=-2.5"), plain);
    EXPECT_EQ(first_pixel("?channel=A&exposure=0"), plain);  // both halves saw 0.1

    const Json metadata = Call(Get("/api/jobs/" + job + "/metadata", alice_), 200);
    EXPECT_EQ(metadata["channels"], (Json{"beauty", "A", "B"}));
    const Json no_albedo = Call(Get(path + "?channel=albedo", alice_), 400);
    EXPECT_TRUE(absl::StartsWith(no_albedo["error"].get<std::string>(), "channel: "));
    EXPECT_TRUE(absl::StrContains(no_albedo["error"].get<std::string>(), "beauty, A, B"));
    EXPECT_TRUE(absl::StartsWith(
        Call(Get(path + "?exposure=9", alice_), 400)["error"].get<std::string>(), "exposure: "));
    Call(Get(path + "?exposure=nan", alice_), 400);
    Call(Get(path + "?exposure=1", bob_), 404);

    // A graded image is named by the preview's version, the exposure and the channel: the
    // browser asks again with it and is answered 304 without an image read or encoded.
    const HttpAnswer graded = dashboard_->Serve(Get(path + "?exposure=1", alice_));
    const std::string etag = HeaderOf(graded, "ETag");
    ASSERT_FALSE(etag.empty());
    HttpRequest again = Get(path + "?exposure=1", alice_);
    again.headers["if-none-match"] = etag;
    EXPECT_EQ(dashboard_->Serve(again).status, 304);
    for (const char* other : {"?exposure=1.5", "?exposure=1&channel=A"}) {
        EXPECT_NE(HeaderOf(dashboard_->Serve(Get(path + other, alice_)), "ETag"), etag) << other;
    }

    const HttpAnswer download = dashboard_->Serve(Get(path + "?download=1", alice_));
    ASSERT_EQ(download.status, 200);
    EXPECT_EQ(HeaderOf(download, "Content-Disposition"),
              "attachment; filename=\"" + job + ".png\"");
}

}  // namespace
}  // namespace lf
