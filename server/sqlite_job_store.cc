#include "server/sqlite_job_store.h"

#include <sqlite3.h>

#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "lf/core/log.h"

namespace lf {

namespace {

using nlohmann::json;

// Times as Unix microseconds; absl::InfinitePast (not yet) as null.
json TimeToJson(absl::Time t) {
    return t == absl::InfinitePast() ? json(nullptr) : json(absl::ToUnixMicros(t));
}
absl::Time TimeFromJson(const json& j) {
    return j.is_null() ? absl::InfinitePast() : absl::FromUnixMicros(j.get<int64_t>());
}

json BlobToJson(const BlobRef& b) { return {{"path", b.path}, {"hash", b.hash}, {"size", b.size}}; }
BlobRef BlobFromJson(const json& j) {
    return {j.at("path").get<std::string>(), j.at("hash").get<std::string>(),
            j.at("size").get<uint64_t>()};
}

// The record as JSON: a proven format, readable with the sqlite3 shell, and new fields need no
// schema change.
std::string RecordToJson(const JobRecord& r) {
    json files = json::array();
    for (const BlobRef& f : r.spec.files) files.push_back(BlobToJson(f));
    const JobSpec& s = r.spec;
    return json{
        {"id", r.id},
        {"seq", r.seq},
        {"spec",
         {{"name", s.name},
          {"scene", BlobToJson(s.scene)},
          {"files", files},
          {"width", s.plan.width},
          {"height", s.plan.height},
          {"spp", s.plan.spp},
          {"tile", s.plan.tile},
          {"passes", s.plan.passes},
          {"seed", s.seed},
          {"max_depth", s.max_depth},
          {"method", s.method},
          {"radiosity",
           {{"patches", s.radiosity.patches},
            {"patch_size", s.radiosity.patch_size},
            {"solver", s.radiosity.solver},
            {"tolerance", s.radiosity.tolerance},
            {"max_iterations", s.radiosity.max_iterations},
            {"display", s.radiosity.display},
            {"sweep_tasks", s.radiosity.sweep_tasks},
            {"max_patches", s.radiosity.max_patches}}},
          {"adaptive",
           {{"target_error", s.adaptive.target_error},
            {"time_limit", s.adaptive.time_limit},
            {"max_spp", s.adaptive.max_spp}}},
          {"priority", s.priority},
          {"scene_hash", s.scene_hash},
          {"request_id", s.request_id}}},
        {"state", int(r.state)},
        {"error", r.error},
        {"last_error", r.last_error},
        {"submitted", TimeToJson(r.submitted)},
        {"started", TimeToJson(r.started)},
        {"finished", TimeToJson(r.finished)},
        {"tasks_total", r.tasks_total},
        {"tasks_done", r.tasks_done},
        {"tasks_running", r.tasks_running},
        {"retries", r.retries},
        {"tasks_leased", r.tasks_leased},
        {"samples", r.stats.samples},
        {"rays", r.stats.rays},
        {"invalid_samples", r.stats.invalid_samples},
        {"result_path", r.result_path},
    }
        .dump();
}

absl::StatusOr<JobRecord> RecordFromJson(std::string_view text) {
    try {
        const json j = json::parse(text);
        JobRecord r;
        r.id = j.at("id").get<std::string>();
        r.seq = j.at("seq").get<uint64_t>();
        const json& s = j.at("spec");
        r.spec.name = s.at("name").get<std::string>();
        r.spec.scene = BlobFromJson(s.at("scene"));
        for (const json& f : s.at("files")) r.spec.files.push_back(BlobFromJson(f));
        r.spec.plan.width = s.at("width").get<int>();
        r.spec.plan.height = s.at("height").get<int>();
        r.spec.plan.spp = s.at("spp").get<uint64_t>();
        r.spec.plan.tile = s.at("tile").get<int>();
        r.spec.plan.passes = s.at("passes").get<int>();
        r.spec.seed = s.at("seed").get<uint64_t>();
        r.spec.max_depth = s.at("max_depth").get<int>();
        r.spec.method = s.value("method", "path");
        if (s.contains("radiosity")) {
            const auto& rad = s.at("radiosity");
            r.spec.radiosity = {rad.at("patches").get<int64_t>(),
                                rad.at("patch_size").get<double>(),
                                rad.at("solver").get<std::string>(),
                                rad.at("tolerance").get<double>(),
                                rad.at("max_iterations").get<int>(),
                                rad.at("display").get<std::string>(),
                                rad.value("sweep_tasks", RadiositySettings().sweep_tasks),
                                rad.value("max_patches", int64_t(0))};
        }
        if (s.contains("adaptive")) {
            const auto& a = s.at("adaptive");
            r.spec.adaptive = {a.at("target_error").get<double>(), a.at("time_limit").get<double>(),
                               a.at("max_spp").get<uint64_t>()};
        }
        r.spec.priority = s.at("priority").get<int>();
        r.spec.scene_hash = s.at("scene_hash").get<std::string>();
        r.spec.request_id = s.value("request_id", "");
        r.state = JobState(j.at("state").get<int>());
        r.error = j.at("error").get<std::string>();
        r.last_error = j.value("last_error", "");
        r.submitted = TimeFromJson(j.at("submitted"));
        r.started = TimeFromJson(j.at("started"));
        r.finished = TimeFromJson(j.at("finished"));
        r.tasks_total = j.at("tasks_total").get<int>();
        r.tasks_done = j.at("tasks_done").get<int>();
        r.tasks_running = j.at("tasks_running").get<int>();
        r.retries = j.at("retries").get<int>();
        r.tasks_leased = j.value("tasks_leased", 0);
        r.stats.samples = j.at("samples").get<uint64_t>();
        r.stats.rays = j.at("rays").get<uint64_t>();
        r.stats.invalid_samples = j.at("invalid_samples").get<uint64_t>();
        r.result_path = j.at("result_path").get<std::string>();
        return r;
    } catch (const json::exception& e) {
        return absl::DataLossError(
            absl::StrCat("a job record in the store is unreadable: ", e.what()));
    }
}

// The connection's last error. A full disk says so in its code, so that the client's message
// is plain; anything else is the server's problem.
absl::Status StoreError(sqlite3* db) {
    const std::string message = absl::StrCat("job store: ", sqlite3_errmsg(db));
    if ((sqlite3_extended_errcode(db) & 0xff) == SQLITE_FULL) {
        return absl::ResourceExhaustedError(message);
    }
    return absl::InternalError(message);
}

// A prepared statement, finalized on scope exit.
class Statement {
  public:
    Statement(sqlite3* db, const char* sql) : db_(db) {
        rc_ = sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr);
    }
    ~Statement() { sqlite3_finalize(stmt_); }
    Statement(const Statement&) = delete;
    Statement& operator=(const Statement&) = delete;

    Statement& Bind(int i, std::string_view text) {
        if (rc_ == SQLITE_OK) {
            rc_ = sqlite3_bind_text(stmt_, i, text.data(), int(text.size()), SQLITE_TRANSIENT);
        }
        return *this;
    }
    Statement& BindBlob(int i, std::string_view bytes) {
        if (rc_ == SQLITE_OK) {
            rc_ = sqlite3_bind_blob(stmt_, i, bytes.data(), int(bytes.size()), SQLITE_TRANSIENT);
        }
        return *this;
    }
    Statement& Bind(int i, int64_t value) {
        if (rc_ == SQLITE_OK) rc_ = sqlite3_bind_int64(stmt_, i, value);
        return *this;
    }
    // True while there is a row; check status() after false.
    bool Step() {
        if (rc_ != SQLITE_OK && rc_ != SQLITE_ROW) return false;
        rc_ = sqlite3_step(stmt_);
        if (rc_ == SQLITE_ROW) return true;
        if (rc_ == SQLITE_DONE) rc_ = SQLITE_OK;
        return false;
    }
    absl::Status status() const {
        if (rc_ == SQLITE_OK || rc_ == SQLITE_ROW) return absl::OkStatus();
        return StoreError(db_);
    }
    std::string_view Column(int i) const {
        const void* data = sqlite3_column_blob(stmt_, i);
        return {static_cast<const char*>(data), size_t(sqlite3_column_bytes(stmt_, i))};
    }
    int64_t ColumnInt(int i) const { return sqlite3_column_int64(stmt_, i); }

  private:
    sqlite3* db_;
    sqlite3_stmt* stmt_ = nullptr;
    int rc_;
};

absl::Status Exec(sqlite3* db, const char* sql) {
    if (sqlite3_exec(db, sql, nullptr, nullptr, nullptr) == SQLITE_OK) return absl::OkStatus();
    return StoreError(db);
}

}  // namespace

absl::StatusOr<std::unique_ptr<SqliteJobStore>> SqliteJobStore::Open(const std::string& path) {
    sqlite3* db = nullptr;
    if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
        SQLITE_OK) {
        absl::Status s = absl::UnavailableError(
            absl::StrCat(path, ": cannot open the job store: ", db ? sqlite3_errmsg(db) : "?"));
        sqlite3_close(db);
        return s;
    }
    std::unique_ptr<SqliteJobStore> store(new SqliteJobStore(db));
    // synchronous=FULL: a commit is on disk when it returns, so what was acknowledged survives
    // a crash of the process or of the machine. The busy timeout only matters for a second
    // process (the sqlite3 shell) reading at the same time.
    if (absl::Status s =
            Exec(db,
                 "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL;"
                 "PRAGMA busy_timeout=5000;"
                 "CREATE TABLE IF NOT EXISTS jobs (id TEXT PRIMARY KEY,"
                 "  seq INTEGER NOT NULL, final INTEGER NOT NULL, record TEXT NOT NULL);"
                 "CREATE TABLE IF NOT EXISTS task_results (job TEXT NOT NULL,"
                 "  task INTEGER NOT NULL, sums BLOB NOT NULL,"
                 "  PRIMARY KEY (job, task));"
                 "CREATE INDEX IF NOT EXISTS jobs_by_request ON jobs ("
                 "  json_extract(record, '$.spec.request_id'));");
        !s.ok()) {
        return absl::Status(s.code(), absl::StrCat(path, ": ", s.message()));
    }
    return store;
}

SqliteJobStore::SqliteJobStore(sqlite3* db) : db_(db), writer_([this] { WriterLoop(); }) {}

SqliteJobStore::~SqliteJobStore() {
    {
        std::lock_guard<std::mutex> lock(queue_mutex_);
        stop_ = true;
    }
    queued_cv_.notify_all();
    writer_.join();
    sqlite3_close(db_);
}

uint64_t SqliteJobStore::QueuePut(const JobRecord& job) {
    return Queue({job.id, job.seq, IsFinal(job.state), RecordToJson(job)});
}

uint64_t SqliteJobStore::QueueTaskDone(const JobRecord& job, int task, std::string result) {
    return Queue({job.id, job.seq, IsFinal(job.state), RecordToJson(job), task, std::move(result)});
}

uint64_t SqliteJobStore::Queue(Write write) {
    std::lock_guard<std::mutex> lock(queue_mutex_);
    queue_.push_back(std::move(write));
    queued_cv_.notify_one();
    return ++last_ticket_;
}

absl::Status SqliteJobStore::WaitDurable(uint64_t ticket) {
    std::unique_lock<std::mutex> lock(queue_mutex_);
    durable_cv_.wait(lock, [&] { return durable_ >= ticket; });
    for (const auto& [first, last, error] : failed_) {
        if (first <= ticket && ticket <= last) return error;
    }
    return absl::OkStatus();
}

void SqliteJobStore::WriterLoop() {
    std::unique_lock<std::mutex> lock(queue_mutex_);
    while (true) {
        queued_cv_.wait(lock, [&] { return stop_ || !queue_.empty(); });
        if (queue_.empty()) return;  // stopping, and everything is committed
        std::deque<Write> batch;
        batch.swap(queue_);
        const uint64_t last = last_ticket_, first = last - batch.size() + 1;
        lock.unlock();
        const absl::Status status = Commit(batch);
        if (!status.ok()) {
            // Writes nobody waits for (leases) are lost here but for this line; the next write
            // of their job carries the state again.
            std::set<std::string> jobs;
            for (const Write& w : batch) jobs.insert(w.job_id);
            NamedLogger("store")->error("job={} commit of {} writes failed: {}",
                                        absl::StrJoin(jobs, ","), batch.size(),
                                        std::string(status.message()));
        }
        lock.lock();
        if (!status.ok()) failed_.emplace_back(first, last, status);
        durable_ = last;
        durable_cv_.notify_all();
    }
}

absl::Status SqliteJobStore::Commit(const std::deque<Write>& batch) {
    // Only the newest record of a job in the batch is written: the earlier ones would be
    // replaced within the same transaction anyway.
    std::map<std::string_view, size_t> newest;
    for (size_t i = 0; i < batch.size(); ++i) newest[batch[i].job_id] = i;
    std::lock_guard<std::mutex> lock(db_mutex_);
    if (absl::Status s = Exec(db_, "BEGIN IMMEDIATE"); !s.ok()) return s;
    absl::Status status;
    for (size_t i = 0; i < batch.size() && status.ok(); ++i) {
        const Write& w = batch[i];
        if (w.task >= 0) {
            Statement put(
                db_, "INSERT OR REPLACE INTO task_results (job, task, sums) VALUES (?1, ?2, ?3)");
            put.Bind(1, w.job_id).Bind(2, int64_t(w.task)).BindBlob(3, w.result).Step();
            status = put.status();
        }
        if (!status.ok() || newest[w.job_id] != i) continue;
        Statement put(
            db_, "INSERT OR REPLACE INTO jobs (id, seq, final, record) VALUES (?1, ?2, ?3, ?4)");
        put.Bind(1, w.job_id).Bind(2, int64_t(w.seq)).Bind(3, int64_t(w.final));
        put.Bind(4, w.record).Step();
        status = put.status();
        if (status.ok() && w.final) {
            Statement drop(db_, "DELETE FROM task_results WHERE job = ?1");
            drop.Bind(1, w.job_id).Step();
            status = drop.status();
        }
    }
    if (status.ok()) status = Exec(db_, "COMMIT");
    if (!status.ok()) Exec(db_, "ROLLBACK").IgnoreError();
    return status;
}

absl::StatusOr<JobRecord> SqliteJobStore::Get(const std::string& id) const {
    std::lock_guard<std::mutex> lock(db_mutex_);
    Statement get(db_, "SELECT record FROM jobs WHERE id = ?1");
    if (get.Bind(1, id).Step()) return RecordFromJson(get.Column(0));
    if (!get.status().ok()) return get.status();
    return absl::NotFoundError("no job " + id);
}

std::vector<JobRecord> SqliteJobStore::List() const {
    std::lock_guard<std::mutex> lock(db_mutex_);
    std::vector<JobRecord> jobs;
    Statement list(db_, "SELECT record FROM jobs ORDER BY seq DESC");
    while (list.Step()) {
        // An unreadable record is skipped rather than hiding every other job.
        if (absl::StatusOr<JobRecord> job = RecordFromJson(list.Column(0)); job.ok()) {
            jobs.push_back(std::move(*job));
        }
    }
    return jobs;
}

std::optional<std::string> SqliteJobStore::FindRequest(const std::string& request_id) const {
    std::lock_guard<std::mutex> lock(db_mutex_);
    Statement find(db_, "SELECT id FROM jobs WHERE json_extract(record, '$.spec.request_id') = ?1");
    if (find.Bind(1, request_id).Step()) return std::string(find.Column(0));
    return std::nullopt;
}

absl::StatusOr<std::map<int, std::string>> SqliteJobStore::TaskResults(
    const std::string& id) const {
    std::lock_guard<std::mutex> lock(db_mutex_);
    std::map<int, std::string> results;
    Statement get(db_, "SELECT task, sums FROM task_results WHERE job = ?1");
    get.Bind(1, id);
    while (get.Step()) results[int(get.ColumnInt(0))] = std::string(get.Column(1));
    if (!get.status().ok()) return get.status();
    return results;
}

}  // namespace lf
