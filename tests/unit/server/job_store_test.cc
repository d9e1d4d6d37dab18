// The JobStore contract, which every store satisfies (in memory and SQLite alike): pages newest
// first, the retention query, request ids unique, deletes; and the stored record format, which
// belongs to the interface: states by name, the integer states of old records (the first form,
// legacy_job_records.h) still read, an unknown name a clear error. Then what only SQLite has:
// databases of the first and the second schema are upgraded in place.
#include "lf/server/job_store.h"

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <filesystem>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>

#include "absl/strings/str_cat.h"
#include "legacy_job_records.h"
#include "lf/core/aov.h"
#include "lf/server/job_record_codec.h"
#include "lf/server/legacy_job_record.h"
#include "lf/server/sqlite_job_store.h"
#include "test_dir.h"

namespace lf {
namespace {

namespace fs = std::filesystem;

fs::path TestDir() {
    const fs::path dir = lf::testing::FreshTestDir("lf_jobstore");
    return dir;
}

JobRecord Record(const std::string& id, uint64_t seq, JobState state = JobState::kRunning) {
    JobRecord r;
    r.id = id;
    r.seq = seq;
    r.spec.name = "job " + id;
    r.state = state;
    r.submitted = absl::FromUnixSeconds(1000 + int64_t(seq));
    if (IsFinal(state)) r.finished = absl::FromUnixSeconds(2000 + int64_t(seq));
    return r;
}

std::vector<std::string> Ids(const absl::StatusOr<std::vector<JobRecord>>& jobs) {
    EXPECT_TRUE(jobs.ok()) << jobs.status();
    std::vector<std::string> ids;
    if (jobs.ok()) {
        for (const JobRecord& j : *jobs) ids.push_back(j.id);
    }
    return ids;
}

struct InMemory {
    std::unique_ptr<JobStore> Open(const fs::path&) { return std::make_unique<InMemoryJobStore>(); }
};
struct Sqlite {
    std::unique_ptr<JobStore> Open(const fs::path& dir) {
        absl::StatusOr<std::unique_ptr<SqliteJobStore>> store =
            SqliteJobStore::Open((dir / "jobs.db").string());
        EXPECT_TRUE(store.ok()) << store.status();
        return std::move(*store);
    }
};

template <class Factory>
class JobStoreContract : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = TestDir();
        store_ = Factory().Open(dir_);
    }
    void TearDown() override {
        store_.reset();
        fs::remove_all(dir_);
    }
    fs::path dir_;
    std::unique_ptr<JobStore> store_;
};

using Stores = ::testing::Types<InMemory, Sqlite>;
TYPED_TEST_SUITE(JobStoreContract, Stores);

TYPED_TEST(JobStoreContract, ListsPagesNewestFirst) {
    for (uint64_t seq = 1; seq <= 5; ++seq) {
        ASSERT_TRUE(this->store_->Put(Record(absl::StrCat("j", seq), seq)).ok());
    }
    EXPECT_EQ(Ids(this->store_->List()), (std::vector<std::string>{"j5", "j4", "j3", "j2", "j1"}));
    EXPECT_EQ(Ids(this->store_->List({.limit = 2})), (std::vector<std::string>{"j5", "j4"}));
    EXPECT_EQ(Ids(this->store_->List({.before_seq = 4, .limit = 2})),
              (std::vector<std::string>{"j3", "j2"}));
    EXPECT_EQ(Ids(this->store_->List({.before_seq = 2, .limit = 2})),
              (std::vector<std::string>{"j1"}));
}

TYPED_TEST(JobStoreContract, RetentionQueryFindsOnlyJobsEndedBeforeTheTime) {
    ASSERT_TRUE(this->store_->Put(Record("running", 1)).ok());
    ASSERT_TRUE(this->store_->Put(Record("old", 2, JobState::kSucceeded)).ok());  // ended 2002
    ASSERT_TRUE(this->store_->Put(Record("new", 3, JobState::kFailed)).ok());     // ended 2003
    EXPECT_EQ(Ids(this->store_->List({.ended_before = absl::FromUnixSeconds(2003)})),
              std::vector<std::string>{"old"});
    EXPECT_EQ(Ids(this->store_->List({.ended_before = absl::FromUnixSeconds(9999)})),
              (std::vector<std::string>{"new", "old"}));
}

TYPED_TEST(JobStoreContract, RequestIdsAreUnique) {
    JobRecord a = Record("a", 1), b = Record("b", 2);
    a.spec.request_id = b.spec.request_id = "req";
    ASSERT_TRUE(this->store_->Put(a).ok());
    EXPECT_EQ(this->store_->Put(b).code(), absl::StatusCode::kAlreadyExists);
    EXPECT_EQ(**this->store_->FindRequest("req"), "a");
    EXPECT_FALSE(this->store_->Get("b").ok());
    a.state = JobState::kRunning;  // the same job again is not a clash
    EXPECT_TRUE(this->store_->Put(a).ok());
    EXPECT_FALSE(this->store_->FindRequest("other")->has_value());
    EXPECT_TRUE(this->store_->Put(Record("c", 3)).ok()) << "no request id is no clash";
    EXPECT_TRUE(this->store_->Put(Record("d", 4)).ok());
}

TYPED_TEST(JobStoreContract, DeleteRemovesTheRecordAndTaskResults) {
    ASSERT_TRUE(
        this->store_->WaitDurable(this->store_->QueueTaskDone(Record("a", 1), 0, "sums", {})).ok());
    ASSERT_TRUE(this->store_->Put(Record("b", 2)).ok());
    ASSERT_TRUE(this->store_->Delete("a").ok());
    EXPECT_EQ(this->store_->Get("a").status().code(), absl::StatusCode::kNotFound);
    EXPECT_TRUE(this->store_->TaskResults("a")->empty());
    EXPECT_EQ(Ids(this->store_->List()), std::vector<std::string>{"b"});
    EXPECT_TRUE(this->store_->Delete("a").ok()) << "nothing to delete is not an error";
}

TEST(JobRecordCodec, StatesAreStoredByName) {
    for (JobState s : {JobState::kQueued, JobState::kRunning, JobState::kSucceeded,
                       JobState::kFailed, JobState::kCancelled}) {
        const nlohmann::json stored = nlohmann::json::parse(EncodeJobRecord(Record("a", 1, s)));
        EXPECT_EQ(stored.at("state"), JobStateName(s));
        EXPECT_EQ(DecodeJobRecord(stored.dump())->state, s);
    }
}

TEST(JobRecordCodec, IntegerStatesOfOldRecordsStillRead) {
    nlohmann::json stored = nlohmann::json::parse(testing::kLegacyRecordA);
    stored["state"] = 3;  // kFailed's position when states were stored so
    EXPECT_EQ(DecodeLegacyJobRecord(stored.dump())->state, JobState::kFailed);
}

TEST(JobRecordCodec, CameraAndResolutionSurviveAndOldRecordsHaveNone) {
    JobRecord job = Record("a", 1);
    job.spec.scene_options = {.camera = "Side", .width = 640, .height = 360};
    nlohmann::json stored = nlohmann::json::parse(EncodeJobRecord(job));
    const absl::StatusOr<JobRecord> back = DecodeJobRecord(stored.dump());
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->spec.scene_options.camera, "Side");
    EXPECT_EQ(back->spec.scene_options.width, 640);
    EXPECT_EQ(back->spec.scene_options.height, 360);
    // The first form, of a job with camera "Side" at 640 x 360.
    stored = nlohmann::json::parse(testing::kLegacyRepresentativeRecords[0]);
    stored["spec"].erase("camera");
    stored["spec"].erase("resolution");
    const absl::StatusOr<JobRecord> old = DecodeLegacyJobRecord(stored.dump());
    ASSERT_TRUE(old.ok()) << old.status();
    EXPECT_EQ(old->spec.scene_options.camera, "");
    EXPECT_EQ(old->spec.scene_options.width, 0);
}

// --sky travels in the record as in RenderParams (a server restart keeps it).
// Job management (issue 30): the job's limits, its workers' failures and its pause survive;
// a record from before them reads with the defaults.
TEST(JobRecordCodec, JobManagementSurvivesAndOldRecordsHaveTheDefaults) {
    JobRecord job = Record("a", 1);
    job.spec.max_attempts = 7;
    job.spec.blocklist_after = 2;
    job.worker_failures = {{"w1", 2, "no GPU"}, {"w2", 1, "disk full"}};
    job.paused = true;
    job.paused_for = absl::Seconds(90);
    job.paused_at = absl::FromUnixSeconds(1'000'000);
    nlohmann::json stored = nlohmann::json::parse(EncodeJobRecord(job));
    const absl::StatusOr<JobRecord> back = DecodeJobRecord(stored.dump());
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->spec.max_attempts, 7);
    EXPECT_EQ(back->spec.blocklist_after, 2);
    ASSERT_EQ(back->worker_failures.size(), 2u);
    EXPECT_EQ(back->worker_failures[0].worker, "w1");
    EXPECT_EQ(back->worker_failures[0].failures, 2);
    EXPECT_EQ(back->worker_failures[0].last_error, "no GPU");
    EXPECT_EQ(back->Blocklisted().size(), 1u);
    EXPECT_TRUE(back->paused);
    EXPECT_EQ(back->paused_for, absl::Seconds(90));
    EXPECT_EQ(back->paused_at, absl::FromUnixSeconds(1'000'000));
    for (const char* field : {"worker_failures", "paused", "paused_for_us", "paused_at_unix_us"}) {
        stored.erase(field);
    }
    for (const char* field : {"max_attempts", "blocklist_after"}) stored["spec"].erase(field);
    const absl::StatusOr<JobRecord> old = DecodeJobRecord(stored.dump());
    ASSERT_TRUE(old.ok()) << old.status();
    EXPECT_EQ(old->spec.max_attempts, kDefaultMaxAttempts);
    EXPECT_EQ(old->spec.blocklist_after, kDefaultBlocklistAfter);
    EXPECT_TRUE(old->worker_failures.empty());
    EXPECT_FALSE(old->paused);
    EXPECT_EQ(old->paused_for, absl::ZeroDuration());
    EXPECT_EQ(old->paused_at, absl::InfinitePast());
}

TEST(JobRecordCodec, SkySurvives) {
    JobRecord job = Record("a", 1);
    job.spec.scene_options.sky = "../maps/sky.hdr";
    const absl::StatusOr<JobRecord> back = DecodeJobRecord(EncodeJobRecord(job));
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->spec.scene_options.sky, "../maps/sky.hdr");
}

TEST(JobRecordCodec, FilterClampAndAovsSurviveAndOldRecordsHaveNone) {
    JobRecord job = Record("a", 1);
    job.spec.scene_options.filter = PixelFilter{PixelFilter::Type::kBlackmanHarris, 2.5};
    job.spec.clamp = 12.5;
    job.spec.aovs = kAovAlbedo | kAovDepth;
    nlohmann::json stored = nlohmann::json::parse(EncodeJobRecord(job));
    const absl::StatusOr<JobRecord> back = DecodeJobRecord(stored.dump());
    ASSERT_TRUE(back.ok()) << back.status();
    ASSERT_TRUE(back->spec.scene_options.filter.has_value());
    EXPECT_EQ(back->spec.scene_options.filter->type, PixelFilter::Type::kBlackmanHarris);
    EXPECT_EQ(back->spec.scene_options.filter->width, 2.5);
    EXPECT_EQ(back->spec.clamp, 12.5);
    EXPECT_EQ(back->spec.aovs, uint32_t(kAovAlbedo | kAovDepth));
    stored["spec"]["params"]["filter_type"] = "FILTER_LANCZOS";
    EXPECT_EQ(DecodeJobRecord(stored.dump()).status().code(), absl::StatusCode::kDataLoss);
    // The first form, of a job with a filter, a clamp and AOVs.
    stored = nlohmann::json::parse(testing::kLegacyRepresentativeRecords[0]);
    stored["spec"]["filter"]["type"] = "lanczos";
    EXPECT_EQ(DecodeLegacyJobRecord(stored.dump()).status().code(), absl::StatusCode::kDataLoss);
    for (const char* key : {"filter", "clamp", "aovs"}) stored["spec"].erase(key);
    const absl::StatusOr<JobRecord> old = DecodeLegacyJobRecord(stored.dump());
    ASSERT_TRUE(old.ok()) << old.status();
    EXPECT_FALSE(old->spec.scene_options.filter.has_value());
    EXPECT_EQ(old->spec.clamp, 0);
    EXPECT_EQ(old->spec.aovs, 0u);
}

// A setting the record stores by name (`key`): each of `values` survives, the default is stored
// by name (the first form: as `default_name`), a name no build knows is data loss (the first
// form's naming it), and a record without the key reads as `before`, what jobs rendered with
// before the setting existed.
template <typename T>
void ExpectNamedSettingSurvives(const std::string& key, T JobSpec::*field,
                                std::initializer_list<T> values, const std::string& default_name,
                                T before) {
    for (const T value : values) {
        JobRecord job = Record("a", 1);
        job.spec.*field = value;
        const absl::StatusOr<JobRecord> back = DecodeJobRecord(EncodeJobRecord(job));
        ASSERT_TRUE(back.ok()) << back.status();
        EXPECT_EQ(back->spec.*field, value) << key;
    }
    nlohmann::json params = nlohmann::json::parse(EncodeJobRecord(Record("a", 1)));
    nlohmann::json& param = params["spec"]["params"][key];
    EXPECT_TRUE(param.is_string()) << param;
    param = "halton";
    EXPECT_EQ(DecodeJobRecord(params.dump()).status().code(), absl::StatusCode::kDataLoss);
    params["spec"]["params"].erase(key);
    const absl::StatusOr<JobRecord> unset = DecodeJobRecord(params.dump());
    ASSERT_TRUE(unset.ok()) << unset.status();
    EXPECT_EQ(unset->spec.*field, before) << key;

    nlohmann::json stored = nlohmann::json::parse(testing::kLegacyRecordA);
    EXPECT_EQ(stored.at("spec").at(key), default_name);
    stored["spec"][key] = "halton";
    const absl::StatusOr<JobRecord> unknown = DecodeLegacyJobRecord(stored.dump());
    EXPECT_EQ(unknown.status().code(), absl::StatusCode::kDataLoss);
    EXPECT_NE(unknown.status().message().find(key + " \"halton\""), std::string_view::npos)
        << unknown.status();
    stored["spec"].erase(key);
    const absl::StatusOr<JobRecord> old = DecodeLegacyJobRecord(stored.dump());
    ASSERT_TRUE(old.ok()) << old.status();
    EXPECT_EQ(old->spec.*field, before) << key;
}

// A record written before --sampler was rendered with independent numbers: resumed, its
// remaining tiles must use them too, whatever the default is now.
TEST(JobRecordCodec, SamplerSurvivesAndOldRecordsKeepIndependentNumbers) {
    ExpectNamedSettingSurvives("sampler", &JobSpec::sampler,
                               {SamplerType::kSobol, SamplerType::kIndependent}, "sobol",
                               SamplerType::kIndependent);
}

// Likewise a record from before --light-sampling picked its lights by power.
TEST(JobRecordCodec, LightStrategySurvivesAndOldRecordsKeepPickingByPower) {
    ExpectNamedSettingSurvives("light_strategy", &JobSpec::light_strategy,
                               {LightStrategy::kBvh, LightStrategy::kPower}, "bvh",
                               LightStrategy::kPower);
}

TEST(JobRecordCodec, UnknownStateNameIsAClearError) {
    nlohmann::json stored = nlohmann::json::parse(EncodeJobRecord(Record("a", 1)));
    stored["state"] = "paused";
    const absl::StatusOr<JobRecord> r = DecodeJobRecord(stored.dump());
    EXPECT_EQ(r.status().code(), absl::StatusCode::kDataLoss);
    EXPECT_NE(r.status().message().find("unknown job state \"paused\""), std::string_view::npos)
        << r.status();
    stored["state"] = 17;
    EXPECT_EQ(DecodeJobRecord(stored.dump()).status().code(), absl::StatusCode::kDataLoss);
}

// A database as the first schema made it: records (of the first form) only, states by position,
// the request id inside the JSON.
void WriteVersion0Database(const fs::path& path, const std::vector<std::string_view>& records) {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(db,
                           "CREATE TABLE jobs (id TEXT PRIMARY KEY, seq INTEGER NOT NULL,"
                           "  final INTEGER NOT NULL, record TEXT NOT NULL);"
                           "CREATE TABLE task_results (job TEXT NOT NULL, task INTEGER NOT NULL,"
                           "  sums BLOB NOT NULL, PRIMARY KEY (job, task));"
                           "CREATE INDEX jobs_by_request ON jobs ("
                           "  json_extract(record, '$.spec.request_id'));",
                           nullptr, nullptr, nullptr),
              SQLITE_OK);
    for (const std::string_view text : records) {
        nlohmann::json record = nlohmann::json::parse(text);
        const JobState state = *JobStateFromName(record.at("state").get<std::string>());
        record["state"] = int(state);
        const std::string sql = "INSERT INTO jobs VALUES ('" + record.at("id").get<std::string>() +
                                "', " + std::to_string(record.at("seq").get<uint64_t>()) + ", " +
                                std::to_string(int(IsFinal(state))) + ", '" + record.dump() + "')";
        ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
    }
    sqlite3_close(db);
}

TEST(SqliteJobStoreUpgrade, FirstSchemaDatabaseIsUpgradedAndReadsAsBefore) {
    const fs::path dir = TestDir();
    // Record("done", 1, JobState::kSucceeded), and Record("running", 2) with request id "req-2"
    WriteVersion0Database(dir / "jobs.db",
                          {testing::kLegacyRecordDone, testing::kLegacyRecordRunning});
    {
        absl::StatusOr<std::unique_ptr<SqliteJobStore>> store =
            SqliteJobStore::Open((dir / "jobs.db").string());
        ASSERT_TRUE(store.ok()) << store.status();
        EXPECT_EQ(Ids((*store)->List()), (std::vector<std::string>{"running", "done"}));
        EXPECT_EQ((*store)->Get("done")->state, JobState::kSucceeded);
        EXPECT_EQ(**(*store)->FindRequest("req-2"), "running");
        EXPECT_EQ(Ids((*store)->List({.ended_before = absl::FromUnixSeconds(9999)})),
                  std::vector<std::string>{"done"});
        JobRecord clash = Record("clash", 3);
        clash.spec.request_id = "req-2";
        EXPECT_EQ((*store)->Put(clash).code(), absl::StatusCode::kAlreadyExists);
    }
    // Upgraded once: the records now carry names, and opening again changes nothing.
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "jobs.db").c_str(), &db), SQLITE_OK);
    sqlite3_stmt* stmt = nullptr;
    sqlite3_prepare_v2(db, "SELECT json_extract(record, '$.state') FROM jobs WHERE id = 'done'", -1,
                       &stmt, nullptr);
    ASSERT_EQ(sqlite3_step(stmt), SQLITE_ROW);
    EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0)), "succeeded");
    sqlite3_finalize(stmt);
    sqlite3_close(db);
    EXPECT_TRUE(SqliteJobStore::Open((dir / "jobs.db").string()).ok());
    fs::remove_all(dir);
}

// A database as version 2 of the store left it: task results without their history.
void WriteVersion2Database(const fs::path& path, const JobRecord& job) {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    const std::string sql = absl::StrCat(
        "CREATE TABLE jobs (id TEXT PRIMARY KEY,"
        "  seq INTEGER NOT NULL, final INTEGER NOT NULL, record TEXT NOT NULL,"
        "  request_id TEXT NOT NULL DEFAULT '', finished INTEGER);"
        "CREATE TABLE task_results (job TEXT NOT NULL,"
        "  task INTEGER NOT NULL, sums BLOB NOT NULL,"
        "  PRIMARY KEY (job, task));"
        "CREATE UNIQUE INDEX jobs_by_request_id ON jobs (request_id) WHERE request_id != '';"
        "CREATE INDEX jobs_by_seq ON jobs (seq);"
        "CREATE INDEX ended_jobs ON jobs (finished) WHERE final = 1;"
        "INSERT INTO jobs (id, seq, final, record) VALUES ('",
        job.id, "', ", job.seq, ", 0, '", EncodeJobRecord(job),
        "');"
        "INSERT INTO task_results VALUES ('",
        job.id, "', 0, 'sums');PRAGMA user_version = 2;");
    ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK)
        << sqlite3_errmsg(db);
    sqlite3_close(db);
}

TEST(SqliteJobStoreUpgrade, SecondSchemaDatabaseKeepsItsResultsAndRecordsTaskHistories) {
    const fs::path dir = TestDir();
    const fs::path path = dir / "jobs.db";
    WriteVersion2Database(path, Record("running", 1));
    const TaskHistory history{2, 1, "node1/host-12", absl::FromUnixSeconds(10),
                              absl::FromUnixSeconds(13)};
    {
        absl::StatusOr<std::unique_ptr<SqliteJobStore>> store = SqliteJobStore::Open(path.string());
        ASSERT_TRUE(store.ok()) << store.status();
        absl::StatusOr<std::map<int, JobStore::RecordedTask>> results =
            (*store)->TaskResults("running");
        ASSERT_TRUE(results.ok()) << results.status();
        ASSERT_EQ(results->size(), 1u);
        EXPECT_EQ(results->at(0).result, "sums");
        EXPECT_EQ(results->at(0).history.attempts, 0) << "recorded before histories were";
        EXPECT_EQ(results->at(0).history.worker, "");
        ASSERT_TRUE((*store)
                        ->WaitDurable(
                            (*store)->QueueTaskDone(*(*store)->Get("running"), 1, "more", history))
                        .ok());
    }
    absl::StatusOr<std::unique_ptr<SqliteJobStore>> store = SqliteJobStore::Open(path.string());
    ASSERT_TRUE(store.ok()) << store.status();
    absl::StatusOr<std::map<int, JobStore::RecordedTask>> results =
        (*store)->TaskResults("running");
    ASSERT_TRUE(results.ok()) << results.status();
    ASSERT_EQ(results->size(), 2u);
    EXPECT_EQ(results->at(0).result, "sums");
    const TaskHistory& back = results->at(1).history;
    EXPECT_EQ(back.attempts, 2);
    EXPECT_EQ(back.failures, 1);
    EXPECT_EQ(back.worker, "node1/host-12");
    EXPECT_EQ(back.leased, history.leased);
    EXPECT_EQ(back.finished, history.finished);
    fs::remove_all(dir);
}

}  // namespace
}  // namespace lf
