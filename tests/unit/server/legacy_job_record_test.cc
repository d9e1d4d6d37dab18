// Records of the first stored form (lf/server/legacy_job_record.h), printed by its encoder before
// the StoredJob form replaced it (legacy_job_records.h): they decode to the jobs they were
// written from, and a store of that form opened by this server is upgraded, lists them, finds
// them by request id and owner, and recovers the jobs that had not ended.
#include "lf/server/legacy_job_record.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "legacy_job_records.h"
#include "lf/core/aov.h"
#include "lf/server/job_record_codec.h"
#include "lf/server/scheduler.h"
#include "lf/server/sqlite_job_store.h"
#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;
using testing::kLegacyRepresentativeRecords;

BlobRef Blob(const std::string& path, char digit, uint64_t size) {
    return {path, std::string(64, digit), size};
}

// One of each kind of job, each setting away from its default somewhere.
std::vector<JobRecord> RepresentativeJobs() {
    std::vector<JobRecord> jobs;
    {  // a path job with AOVs, a filter, a clamp, a camera and resolution; succeeded
        JobRecord r;
        r.id = "job-path";
        r.seq = 7;
        r.spec.name = "cornell.json";
        r.spec.scene = Blob("cornell.json", 'a', 1234);
        r.spec.files = {Blob("meshes/bunny.obj", 'b', 987654),
                        Blob("textures/wood.png", 'c', 4321)};
        r.spec.scene_options = {.camera = "Side",
                                .width = 640,
                                .height = 360,
                                .filter = PixelFilter{PixelFilter::Type::kBlackmanHarris, 2.5}};
        r.spec.plan = {.width = 640, .height = 360, .spp = 256, .tile = 64, .passes = 4};
        r.spec.seed = 42;
        r.spec.max_depth = 12;
        r.spec.clamp = 12.5;
        r.spec.aovs = kAovAlbedo | kAovNormal | kAovDepth;
        r.spec.sampler = SamplerType::kSobol;
        r.spec.light_strategy = LightStrategy::kBvh;
        r.spec.priority = 3;
        r.spec.scene_hash = std::string(64, 'd');
        r.state = JobState::kSucceeded;
        r.submitted = absl::FromUnixMicros(1700000000123456);
        r.started = absl::FromUnixMicros(1700000001234567);
        r.finished = absl::FromUnixMicros(1700000042345678);
        r.tasks_total = r.tasks_done = 240;
        r.tasks_leased = 243;
        r.retries = 3;
        r.stats = {.samples = 58982400, .rays = 412876800, .invalid_samples = 2};
        r.result_path = "/var/lib/lightfarm/results/job-path.exr";
        jobs.push_back(r);
    }
    {  // an adaptive path job, running
        JobRecord r;
        r.id = "job-adaptive";
        r.seq = 8;
        r.spec.name = "glass.json";
        r.spec.scene = Blob("glass.json", 'e', 555);
        r.spec.plan = {.width = 320, .height = 240, .spp = 16, .tile = 32, .passes = 1};
        r.spec.adaptive = {.target_error = 0.01, .time_limit = 90.5, .max_spp = 4096};
        r.spec.sampler = SamplerType::kIndependent;
        r.spec.light_strategy = LightStrategy::kPower;
        r.spec.scene_hash = std::string(64, 'f');
        r.state = JobState::kRunning;
        r.submitted = absl::FromUnixMicros(1700000100000001);
        r.started = absl::FromUnixMicros(1700000100500000);
        r.tasks_total = 120;
        r.tasks_done = 77;
        r.tasks_running = 4;
        r.tasks_leased = 81;
        r.stats = {.samples = 1228800, .rays = 7372800, .invalid_samples = 0};
        jobs.push_back(r);
    }
    {  // radiosity solved by Jacobi sweeps on the farm, queued
        JobRecord r;
        r.id = "job-radiosity";
        r.seq = 9;
        r.spec.name = "room";
        r.spec.scene = Blob("room.json", '1', 2048);
        r.spec.method = "radiosity";
        r.spec.radiosity = {.patches = 20000,
                            .patch_size = 0.125,
                            .solver = "jacobi",
                            .tolerance = 1e-5,
                            .max_iterations = 300,
                            .display = "smooth",
                            .sweep_tasks = 16,
                            .max_patches = 320000};
        r.spec.plan = {.width = 400, .height = 300, .spp = 4, .tile = 100, .passes = 1};
        r.spec.max_depth = -1;
        r.spec.scene_hash = std::string(64, '2');
        r.state = JobState::kQueued;
        r.submitted = absl::FromUnixMicros(1700000200000000);
        r.tasks_total = 28;
        jobs.push_back(r);
    }
    {  // progressive photon mapping, running after a task failure
        JobRecord r;
        r.id = "job-ppm";
        r.seq = 10;
        r.spec.name = "caustic.json";
        r.spec.scene = Blob("caustic.json", '3', 777);
        r.spec.method = "ppm";
        r.spec.ppm = {.photons_per_pass = 500000, .initial_radius = 0.05, .alpha = 0.7};
        r.spec.plan = {.width = 256, .height = 256, .spp = 64, .tile = 64, .passes = 8};
        r.spec.seed = 7;
        r.spec.scene_hash = std::string(64, '4');
        r.state = JobState::kRunning;
        r.last_error = "worker w1: out of memory building the photon map";
        r.submitted = absl::FromUnixMicros(1700000300000000);
        r.started = absl::FromUnixMicros(1700000300250000);
        r.tasks_total = 8;
        r.tasks_done = 2;
        r.tasks_running = 2;
        r.retries = 1;
        r.tasks_leased = 5;
        r.stats = {.samples = 131072, .rays = 900000, .invalid_samples = 1};
        jobs.push_back(r);
    }
    {  // ended failed, with an owner and a request id
        JobRecord r;
        r.id = "job-failed";
        r.seq = 11;
        r.spec.name = "broken \"scene\"";
        r.spec.scene = Blob("broken.json", '5', 99);
        r.spec.method = "bdpt";
        r.spec.plan = {.width = 64, .height = 48, .spp = 8, .tile = 16, .passes = 2};
        r.spec.scene_hash = std::string(64, '6');
        r.spec.request_id = "req-3f2a";
        r.spec.owner = "alice";
        r.spec.priority = -2;
        r.state = JobState::kFailed;
        r.error = "task 3 failed 3 times: scene.json: shapes[3].vertices[1]: not a finite number";
        r.last_error = "scene.json: shapes[3].vertices[1]: not a finite number";
        r.submitted = absl::FromUnixMicros(1700000400000000);
        r.started = absl::FromUnixMicros(1700000400100000);
        r.finished = absl::FromUnixMicros(1700000409900000);
        r.tasks_total = 24;
        r.tasks_done = 5;
        r.retries = 2;
        r.tasks_leased = 9;
        jobs.push_back(r);
    }
    {  // cancelled before it started, light tracing
        JobRecord r;
        r.id = "job-cancelled";
        r.seq = 12;
        r.spec.name = "lamp";
        r.spec.scene = Blob("lamp.json", '7', 10);
        r.spec.method = "light";
        r.spec.scene_hash = std::string(64, '8');
        r.spec.owner = "bob";
        r.state = JobState::kCancelled;
        r.submitted = absl::FromUnixMicros(1700000500000000);
        r.finished = absl::FromUnixMicros(1700000501000000);
        jobs.push_back(r);
    }
    return jobs;
}

void ExpectSameBlob(const BlobRef& a, const BlobRef& b) {
    EXPECT_EQ(a.path, b.path);
    EXPECT_EQ(a.hash, b.hash);
    EXPECT_EQ(a.size, b.size);
}

void ExpectSameSpec(const JobSpec& a, const JobSpec& b) {
    EXPECT_EQ(a.name, b.name);
    ExpectSameBlob(a.scene, b.scene);
    ASSERT_EQ(a.files.size(), b.files.size());
    for (size_t i = 0; i < a.files.size(); ++i) ExpectSameBlob(a.files[i], b.files[i]);
    EXPECT_EQ(a.scene_options.camera, b.scene_options.camera);
    EXPECT_EQ(a.scene_options.width, b.scene_options.width);
    EXPECT_EQ(a.scene_options.height, b.scene_options.height);
    ASSERT_EQ(a.scene_options.filter.has_value(), b.scene_options.filter.has_value());
    if (a.scene_options.filter) {
        EXPECT_EQ(a.scene_options.filter->type, b.scene_options.filter->type);
        EXPECT_EQ(a.scene_options.filter->width, b.scene_options.filter->width);
    }
    EXPECT_EQ(a.plan.width, b.plan.width);
    EXPECT_EQ(a.plan.height, b.plan.height);
    EXPECT_EQ(a.plan.spp, b.plan.spp);
    EXPECT_EQ(a.plan.tile, b.plan.tile);
    EXPECT_EQ(a.plan.passes, b.plan.passes);
    EXPECT_EQ(a.seed, b.seed);
    EXPECT_EQ(a.max_depth, b.max_depth);
    EXPECT_EQ(a.clamp, b.clamp);
    EXPECT_EQ(a.aovs, b.aovs);
    EXPECT_EQ(a.sampler, b.sampler);
    EXPECT_EQ(a.light_strategy, b.light_strategy);
    EXPECT_EQ(a.method, b.method);
    EXPECT_EQ(a.radiosity.patches, b.radiosity.patches);
    EXPECT_EQ(a.radiosity.patch_size, b.radiosity.patch_size);
    EXPECT_EQ(a.radiosity.solver, b.radiosity.solver);
    EXPECT_EQ(a.radiosity.tolerance, b.radiosity.tolerance);
    EXPECT_EQ(a.radiosity.max_iterations, b.radiosity.max_iterations);
    EXPECT_EQ(a.radiosity.display, b.radiosity.display);
    EXPECT_EQ(a.radiosity.sweep_tasks, b.radiosity.sweep_tasks);
    EXPECT_EQ(a.radiosity.max_patches, b.radiosity.max_patches);
    EXPECT_EQ(a.ppm.photons_per_pass, b.ppm.photons_per_pass);
    EXPECT_EQ(a.ppm.initial_radius, b.ppm.initial_radius);
    EXPECT_EQ(a.ppm.alpha, b.ppm.alpha);
    EXPECT_EQ(a.adaptive.target_error, b.adaptive.target_error);
    EXPECT_EQ(a.adaptive.time_limit, b.adaptive.time_limit);
    EXPECT_EQ(a.adaptive.max_spp, b.adaptive.max_spp);
    EXPECT_EQ(a.priority, b.priority);
    EXPECT_EQ(a.scene_hash, b.scene_hash);
    EXPECT_EQ(a.request_id, b.request_id);
    EXPECT_EQ(a.owner, b.owner);
}

void ExpectSameRecord(const JobRecord& a, const JobRecord& b) {
    SCOPED_TRACE(b.id);
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.seq, b.seq);
    ExpectSameSpec(a.spec, b.spec);
    EXPECT_EQ(a.state, b.state);
    EXPECT_EQ(a.error, b.error);
    EXPECT_EQ(a.last_error, b.last_error);
    EXPECT_EQ(a.submitted, b.submitted);
    EXPECT_EQ(a.started, b.started);
    EXPECT_EQ(a.finished, b.finished);
    EXPECT_EQ(a.tasks_total, b.tasks_total);
    EXPECT_EQ(a.tasks_done, b.tasks_done);
    EXPECT_EQ(a.tasks_running, b.tasks_running);
    EXPECT_EQ(a.retries, b.retries);
    EXPECT_EQ(a.tasks_leased, b.tasks_leased);
    EXPECT_EQ(a.stats.samples, b.stats.samples);
    EXPECT_EQ(a.stats.rays, b.stats.rays);
    EXPECT_EQ(a.stats.invalid_samples, b.stats.invalid_samples);
    EXPECT_EQ(a.result_path, b.result_path);
}

TEST(LegacyJobRecord, DecodesToTheJobsItWasWrittenFrom) {
    const std::vector<JobRecord> jobs = RepresentativeJobs();
    for (size_t i = 0; i < jobs.size(); ++i) {
        const absl::StatusOr<JobRecord> decoded =
            DecodeLegacyJobRecord(kLegacyRepresentativeRecords[i]);
        ASSERT_TRUE(decoded.ok()) << decoded.status();
        ExpectSameRecord(*decoded, jobs[i]);
    }
}

TEST(JobRecordCodec, RepresentativeJobsRoundTrip) {
    for (const JobRecord& job : RepresentativeJobs()) {
        const absl::StatusOr<JobRecord> back = DecodeJobRecord(EncodeJobRecord(job));
        ASSERT_TRUE(back.ok()) << back.status();
        ExpectSameRecord(*back, job);
    }
}

TEST(JobRecordCodec, OldFormIsNotReadAsTheNew) {
    const absl::StatusOr<JobRecord> r = DecodeJobRecord(kLegacyRepresentativeRecords[0]);
    EXPECT_EQ(r.status().code(), absl::StatusCode::kDataLoss);
}

// A database as version 1 of the store left it: the columns it selects on, and records in the
// first form.
void WriteVersion1Database(const fs::path& path) {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(db,
                           "CREATE TABLE jobs (id TEXT PRIMARY KEY,"
                           "  seq INTEGER NOT NULL, final INTEGER NOT NULL, record TEXT NOT NULL,"
                           "  request_id TEXT NOT NULL DEFAULT '', finished INTEGER);"
                           "CREATE TABLE task_results (job TEXT NOT NULL,"
                           "  task INTEGER NOT NULL, sums BLOB NOT NULL,"
                           "  PRIMARY KEY (job, task));"
                           "CREATE UNIQUE INDEX jobs_by_request_id ON jobs (request_id)"
                           "  WHERE request_id != '';"
                           "CREATE INDEX jobs_by_seq ON jobs (seq);"
                           "CREATE INDEX ended_jobs ON jobs (finished) WHERE final = 1;"
                           "PRAGMA user_version = 1;",
                           nullptr, nullptr, nullptr),
              SQLITE_OK);
    for (std::string_view text : kLegacyRepresentativeRecords) {
        const nlohmann::json record = nlohmann::json::parse(text);
        const bool final = IsFinal(*JobStateFromName(record.at("state").get<std::string>()));
        sqlite3_stmt* insert = nullptr;
        ASSERT_EQ(sqlite3_prepare_v2(db, "INSERT INTO jobs VALUES (?1, ?2, ?3, ?4, ?5, ?6)", -1,
                                     &insert, nullptr),
                  SQLITE_OK);
        sqlite3_bind_text(insert, 1, record.at("id").get<std::string>().c_str(), -1,
                          SQLITE_TRANSIENT);
        sqlite3_bind_int64(insert, 2, record.at("seq").get<int64_t>());
        sqlite3_bind_int(insert, 3, final);
        sqlite3_bind_text(insert, 4, text.data(), int(text.size()), SQLITE_TRANSIENT);
        sqlite3_bind_text(insert, 5, record.at("spec").at("request_id").get<std::string>().c_str(),
                          -1, SQLITE_TRANSIENT);
        if (final) sqlite3_bind_int64(insert, 6, record.at("finished").get<int64_t>());
        ASSERT_EQ(sqlite3_step(insert), SQLITE_DONE);
        sqlite3_finalize(insert);
    }
    sqlite3_close(db);
}

std::string StoredRecordText(const fs::path& path, const std::string& id) {
    sqlite3* db = nullptr;
    EXPECT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    sqlite3_stmt* stmt = nullptr;
    sqlite3_prepare_v2(db, "SELECT record FROM jobs WHERE id = ?1", -1, &stmt, nullptr);
    sqlite3_bind_text(stmt, 1, id.c_str(), -1, SQLITE_TRANSIENT);
    std::string text;
    if (sqlite3_step(stmt) == SQLITE_ROW) {
        text = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0));
    }
    sqlite3_finalize(stmt);
    sqlite3_close(db);
    return text;
}

TEST(SqliteJobStoreUpgrade, Version1DatabaseListsAndRecoversItsJobs) {
    const fs::path dir = lf::testing::FreshTestDir("lf_legacy_store");
    const fs::path path = dir / "jobs.db";
    WriteVersion1Database(path);
    const std::vector<JobRecord> jobs = RepresentativeJobs();
    {
        absl::StatusOr<std::unique_ptr<SqliteJobStore>> store = SqliteJobStore::Open(path.string());
        ASSERT_TRUE(store.ok()) << store.status();
        const absl::StatusOr<std::vector<JobRecord>> listed = (*store)->List();
        ASSERT_TRUE(listed.ok()) << listed.status();
        ASSERT_EQ(listed->size(), jobs.size());
        for (size_t i = 0; i < jobs.size(); ++i) {
            ExpectSameRecord((*listed)[i], jobs[jobs.size() - 1 - i]);  // newest first
        }
        EXPECT_EQ(**(*store)->FindRequest("req-3f2a"), "job-failed");
        const absl::StatusOr<std::vector<JobRecord>> alices = (*store)->List({.owner = "alice"});
        ASSERT_TRUE(alices.ok()) << alices.status();
        ASSERT_EQ(alices->size(), 1u);
        EXPECT_EQ(alices->front().id, "job-failed");
        const absl::StatusOr<std::map<JobState, int64_t>> ended = (*store)->CountEnded();
        ASSERT_TRUE(ended.ok()) << ended.status();
        EXPECT_EQ(*ended, (std::map<JobState, int64_t>{{JobState::kSucceeded, 1},
                                                       {JobState::kFailed, 1},
                                                       {JobState::kCancelled, 1}}));

        // The jobs that had not ended are running again, with the settings they were submitted
        // with.
        Scheduler scheduler({}, **store);
        const absl::StatusOr<std::vector<Scheduler::JobRun>> rendered = scheduler.Recover();
        ASSERT_TRUE(rendered.ok()) << rendered.status();
        for (const JobRecord& job : jobs) {
            if (IsFinal(job.state)) continue;
            SCOPED_TRACE(job.id);
            const absl::StatusOr<JobRecord> recovered = scheduler.Get(job.id);
            ASSERT_TRUE(recovered.ok()) << recovered.status();
            EXPECT_FALSE(IsFinal(recovered->state));
            ExpectSameSpec(recovered->spec, job.spec);
        }
    }
    // Upgraded once, to the new form: its records read as such, and opening again keeps them.
    for (const JobRecord& job : jobs) {
        const absl::StatusOr<JobRecord> stored = DecodeJobRecord(StoredRecordText(path, job.id));
        ASSERT_TRUE(stored.ok()) << stored.status();
        ExpectSameSpec(stored->spec, job.spec);
    }
    absl::StatusOr<std::unique_ptr<SqliteJobStore>> again = SqliteJobStore::Open(path.string());
    ASSERT_TRUE(again.ok()) << again.status();
    ExpectSameRecord(*(*again)->Get("job-path"), jobs[0]);
    again->reset();
    fs::remove_all(dir);
}

}  // namespace
}  // namespace lf
