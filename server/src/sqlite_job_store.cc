#include "lf/server/sqlite_job_store.h"

#include <sqlite3.h>

#include <limits>
#include <map>
#include <set>

#include "absl/cleanup/cleanup.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "lf/core/log.h"
#include "lf/core/plural.h"
#include "lf/server/job_record_codec.h"
#include "lf/server/legacy_job_record.h"
#include "lf/server/sqlite_statement.h"

namespace lf {

namespace {

// A stored record, its errors naming the job.
absl::StatusOr<JobRecord> NamingTheJob(std::string_view id, absl::StatusOr<JobRecord> job) {
    if (job.ok()) return job;
    return absl::Status(job.status().code(), absl::StrCat("job store: job ", std::string(id), ": ",
                                                          job.status().message()));
}
absl::StatusOr<JobRecord> Decode(std::string_view id, std::string_view record) {
    return NamingTheJob(id, DecodeJobRecord(record));
}
absl::StatusOr<JobRecord> DecodeLegacy(std::string_view id, std::string_view record) {
    return NamingTheJob(id, DecodeLegacyJobRecord(record));
}

// Schema versions (PRAGMA user_version): 0, records only, states by enum position, request ids
// found inside the JSON; 1, the columns List and FindRequest select on, states by name; 2,
// records in the StoredJob form (lf/server/job_record_codec.h), those before in the legacy form;
// 3, task_results' history column (EncodeTaskHistory; '' for results recorded before); 4, the
// history tables task_stats, job_stats and worker_failure_stats (a store upgraded gains its
// ended jobs in job_stats).
constexpr int kSchemaVersion = 4;

// Removes the history older than SqliteJobStore::kStatsKeptFor.
absl::Status PruneStats(sqlite3* db) {
    const int64_t before = absl::ToUnixMicros(absl::Now() - SqliteJobStore::kStatsKeptFor);
    for (const char* sql :
         {"DELETE FROM task_stats WHERE finished < ?1", "DELETE FROM job_stats WHERE ended < ?1",
          "DELETE FROM worker_failure_stats WHERE ended < ?1"}) {
        Statement prune(db, sql);
        prune.Bind(1, before).Step();
        if (!prune.status().ok()) return prune.status();
    }
    return absl::OkStatus();
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
    // process (the sqlite3 shell) reading at the same time. secure_delete=FAST: Debian builds
    // SQLite to overwrite every deleted byte, which wrote a job's task results (1.7 MB a
    // 128x128 tile) again when it succeeded, in the commit that ends it (19.5 ms of the Cornell
    // box's 1.6 s); FAST still clears deleted records on the tree's pages, not the overflow
    // pages of large ones (task results, large job specs) until SQLite reuses them.
    absl::Status s = Exec(db,
                          "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL;"
                          "PRAGMA busy_timeout=5000; PRAGMA secure_delete=FAST;");
    int64_t found_version = 0;
    bool old = false;
    if (s.ok()) {
        Statement version(db, "PRAGMA user_version");
        if (version.Step()) found_version = version.ColumnInt(0);
        Statement tables(db, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'jobs'");
        old = tables.Step() && found_version < kSchemaVersion;
        s = version.status().ok() ? tables.status() : version.status();
    }
    if (s.ok() && found_version > kSchemaVersion) {
        s = absl::FailedPreconditionError(absl::StrCat(
            "job store version ", found_version, " is newer than this server's (", kSchemaVersion,
            "): run a lightfarm-server as new as the one that wrote it"));
    }
    if (s.ok() && old) s = Migrate(db, found_version);
    if (s.ok()) {
        s = Exec(db,
                 "CREATE TABLE IF NOT EXISTS jobs (id TEXT PRIMARY KEY,"
                 "  seq INTEGER NOT NULL, final INTEGER NOT NULL, record TEXT NOT NULL,"
                 "  request_id TEXT NOT NULL DEFAULT '', finished INTEGER);"
                 "CREATE TABLE IF NOT EXISTS task_results (job TEXT NOT NULL,"
                 "  task INTEGER NOT NULL, sums BLOB NOT NULL, history TEXT NOT NULL DEFAULT '',"
                 "  PRIMARY KEY (job, task));"
                 "CREATE UNIQUE INDEX IF NOT EXISTS jobs_by_request_id ON jobs (request_id)"
                 "  WHERE request_id != '';"
                 "CREATE INDEX IF NOT EXISTS jobs_by_seq ON jobs (seq);"
                 "CREATE INDEX IF NOT EXISTS ended_jobs ON jobs (finished) WHERE final = 1;"
                 // The history (issue 30): times in Unix microseconds; a task's frame is NULL but
                 // for a shot's task of one frame. A task rendered again after a requeue adds a
                 // row; a job keeps only its last end.
                 "CREATE TABLE IF NOT EXISTS task_stats (job TEXT NOT NULL, task INTEGER NOT NULL,"
                 "  finished INTEGER NOT NULL, owner TEXT NOT NULL, worker TEXT NOT NULL,"
                 "  frame INTEGER, cpu_seconds REAL NOT NULL, render_seconds REAL NOT NULL,"
                 "  samples INTEGER NOT NULL, PRIMARY KEY (job, task, finished));"
                 "CREATE INDEX IF NOT EXISTS task_stats_by_finished ON task_stats (finished);"
                 // A submitter's stats read their own rows only.
                 "CREATE INDEX IF NOT EXISTS task_stats_by_owner ON task_stats (owner, finished);"
                 "CREATE TABLE IF NOT EXISTS job_stats (job TEXT PRIMARY KEY, owner TEXT NOT NULL,"
                 "  state TEXT NOT NULL, ended INTEGER NOT NULL);"
                 "CREATE INDEX IF NOT EXISTS job_stats_by_ended ON job_stats (ended);"
                 "CREATE TABLE IF NOT EXISTS worker_failure_stats (job TEXT NOT NULL,"
                 "  ended INTEGER NOT NULL, worker TEXT NOT NULL, owner TEXT NOT NULL,"
                 "  failures INTEGER NOT NULL, PRIMARY KEY (job, ended, worker));"
                 "CREATE INDEX IF NOT EXISTS worker_failure_stats_by_ended"
                 "  ON worker_failure_stats (ended);");
    }
    if (s.ok() && old && found_version < 4) {
        // The jobs that ended before the history: counted by state, without their tasks.
        s = Exec(
            db,
            "INSERT OR IGNORE INTO job_stats (job, owner, state, ended)"
            " SELECT id, json_extract(record, '$.spec.owner'), json_extract(record, '$.state'),"
            " finished FROM jobs WHERE final = 1 AND finished IS NOT NULL");
    }
    if (s.ok()) s = PruneStats(db);
    if (s.ok()) {
        s = Exec(db, absl::StrCat("PRAGMA user_version = ", kSchemaVersion).c_str());
    }
    if (s.ok() && sqlite3_open_v2(path.c_str(), &store->read_db_, SQLITE_OPEN_READWRITE, nullptr) !=
                      SQLITE_OK) {
        s = absl::UnavailableError(
            absl::StrCat("cannot open a reading connection: ",
                         store->read_db_ ? sqlite3_errmsg(store->read_db_) : "?"));
    }
    // A reader of a WAL database waits only while another connection recovers or checkpoints
    // it, briefly; the timeout keeps that from being an error.
    if (s.ok()) s = Exec(store->read_db_, "PRAGMA busy_timeout=5000;");
    if (!s.ok()) return absl::Status(s.code(), absl::StrCat(path, ": ", s.message()));
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
    sqlite3_close(read_db_);
    sqlite3_close(db_);
}

SqliteJobStore::Write SqliteJobStore::PutOf(const JobRecord& job) {
    Write w{job.id};
    w.seq = job.seq;
    w.final = IsFinal(job.state);
    w.drop_results = job.state == JobState::kSucceeded && !job.spec.shot.frames;
    w.request_id = job.spec.request_id;
    if (w.final && job.finished != absl::InfinitePast()) {
        w.finished_us = absl::ToUnixMicros(job.finished);
    }
    w.record = EncodeJobRecord(job);
    w.owner = job.spec.owner;
    w.state = job.state;
    if (w.finished_us) w.worker_failures = job.worker_failures;
    return w;
}

uint64_t SqliteJobStore::QueuePut(const JobRecord& job) { return Queue(PutOf(job)); }

uint64_t SqliteJobStore::QueueTaskDone(const JobRecord& job, int task, std::string result,
                                       const TaskHistory& history) {
    Write w = PutOf(job);
    w.task = task;
    w.result = std::move(result);
    w.history = EncodeTaskHistory(history);
    w.done = history;
    return Queue(std::move(w));
}

uint64_t SqliteJobStore::QueuePutDropping(const JobRecord& job, const std::vector<int>& tasks) {
    Write w = PutOf(job);
    w.drop_tasks = tasks;
    return Queue(std::move(w));
}

uint64_t SqliteJobStore::QueueDelete(const std::string& id) {
    Write w{id};
    w.remove = true;
    return Queue(std::move(w));
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
        const absl::Time start = absl::Now();
        const absl::Status status = Commit(batch);
        write_seconds_.Observe(absl::ToDoubleSeconds(absl::Now() - start));
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
        last_commit_ = status;
        durable_ = last;
        durable_cv_.notify_all();
    }
}

absl::Status SqliteJobStore::Commit(const std::deque<Write>& batch) {
    // Only the newest record of a job in the batch is written: the earlier ones would be
    // replaced, or deleted, within the same transaction anyway.
    std::map<std::string_view, size_t> newest;
    for (size_t i = 0; i < batch.size(); ++i) newest[batch[i].job_id] = i;
    std::lock_guard<std::mutex> lock(db_mutex_);
    if (absl::Status s = Exec(db_, "BEGIN IMMEDIATE"); !s.ok()) return s;
    absl::Status status;
    for (size_t i = 0; i < batch.size() && status.ok(); ++i) {
        const Write& w = batch[i];
        if (w.remove) {
            Statement drop(db_, "DELETE FROM jobs WHERE id = ?1");
            drop.Bind(1, w.job_id).Step();
            Statement drop_results(db_, "DELETE FROM task_results WHERE job = ?1");
            if (drop.status().ok()) drop_results.Bind(1, w.job_id).Step();
            status = drop.status().ok() ? drop_results.status() : drop.status();
            continue;
        }
        if (w.task >= 0) {
            Statement put(db_,
                          "INSERT OR REPLACE INTO task_results (job, task, sums, history)"
                          " VALUES (?1, ?2, ?3, ?4)");
            put.Bind(1, w.job_id).Bind(2, int64_t(w.task)).BindBlob(3, w.result);
            put.Bind(4, w.history).Step();
            status = put.status();
            if (status.ok()) status = RecordTaskStats(w);
        }
        for (size_t k = 0; k < w.drop_tasks.size() && status.ok(); ++k) {
            Statement drop(db_, "DELETE FROM task_results WHERE job = ?1 AND task = ?2");
            drop.Bind(1, w.job_id).Bind(2, int64_t(w.drop_tasks[k])).Step();
            status = drop.status();
        }
        // Every end goes into the history, even one whose record a later write in the batch
        // replaces or deletes (a job deleted as soon as it ended).
        if (status.ok() && w.finished_us) status = RecordJobEnd(w);
        if (!status.ok() || newest[w.job_id] != i) continue;
        // An upsert by id, not INSERT OR REPLACE: a clash of request ids must fail, not delete
        // the other job.
        Statement put(db_,
                      "INSERT INTO jobs (id, seq, final, record, request_id, finished)"
                      " VALUES (?1, ?2, ?3, ?4, ?5, ?6) ON CONFLICT (id) DO UPDATE SET"
                      " seq = excluded.seq, final = excluded.final, record = excluded.record,"
                      " request_id = excluded.request_id, finished = excluded.finished");
        put.Bind(1, w.job_id).Bind(2, int64_t(w.seq)).Bind(3, int64_t(w.final));
        put.Bind(4, w.record).Bind(5, w.request_id).Bind(6, w.finished_us).Step();
        status = put.status();
        if (status.ok() && w.drop_results) {
            Statement drop(db_, "DELETE FROM task_results WHERE job = ?1");
            drop.Bind(1, w.job_id).Step();
            status = drop.status();
        }
    }
    if (status.ok()) status = Exec(db_, "COMMIT");
    if (!status.ok()) Exec(db_, "ROLLBACK").IgnoreError();
    return status;
}

absl::Status SqliteJobStore::RecordTaskStats(const Write& w) {
    const absl::Time finished =
        w.done.finished == absl::InfinitePast() ? absl::Now() : w.done.finished;
    Statement put(db_,
                  "INSERT OR REPLACE INTO task_stats (job, task, finished, owner, worker, frame,"
                  " cpu_seconds, render_seconds, samples)"
                  " VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)");
    put.Bind(1, w.job_id).Bind(2, int64_t(w.task)).Bind(3, absl::ToUnixMicros(finished));
    put.Bind(4, w.owner).Bind(5, w.done.worker);
    put.Bind(6, w.done.frame ? std::optional<int64_t>(*w.done.frame) : std::nullopt);
    put.BindDouble(7, w.done.times.cpu_seconds).BindDouble(8, w.done.times.render_seconds);
    put.Bind(9, int64_t(w.done.samples)).Step();
    return put.status();
}

absl::Status SqliteJobStore::RecordJobEnd(const Write& w) {
    // An ended job's record, written again (a requeued job that ends again) or not: its last
    // end replaces the row, and its failures are those since its requeue cleared them.
    Statement job(db_,
                  "INSERT OR REPLACE INTO job_stats (job, owner, state, ended)"
                  " VALUES (?1, ?2, ?3, ?4)");
    job.Bind(1, w.job_id).Bind(2, w.owner).Bind(3, JobStateName(w.state));
    job.Bind(4, w.finished_us).Step();
    if (!job.status().ok()) return job.status();
    for (const WorkerFailures& f : w.worker_failures) {
        Statement put(db_,
                      "INSERT OR REPLACE INTO worker_failure_stats (job, ended, worker, owner,"
                      " failures) VALUES (?1, ?2, ?3, ?4, ?5)");
        put.Bind(1, w.job_id).Bind(2, w.finished_us).Bind(3, f.worker).Bind(4, w.owner);
        put.Bind(5, int64_t(f.failures)).Step();
        if (!put.status().ok()) return put.status();
    }
    return PruneStats(db_);
}

absl::StatusOr<FarmStats> SqliteJobStore::Stats(const StatsQuery& query) const {
    const int64_t since = query.since == absl::InfinitePast() ? std::numeric_limits<int64_t>::min()
                                                              : absl::ToUnixMicros(query.since);
    StatsAccumulator stats;
    std::lock_guard<std::mutex> lock(read_mutex_);
    // One snapshot for the four queries: a job requeued or ended between two of them would
    // count twice or not at all.
    if (absl::Status s = Exec(read_db_, "BEGIN"); !s.ok()) return s;
    absl::Cleanup end_read = [&] { Exec(read_db_, "COMMIT").IgnoreError(); };
    const auto read = [&](const char* sql, const auto& add) {
        Statement rows(read_db_, sql);
        rows.Bind(1, since);
        if (query.owner) rows.Bind(2, *query.owner);
        while (rows.Step()) add(rows);
        return rows.status();
    };
    absl::Status status = read(
        // A job requeued since it ended counts as active, not by its earlier end.
        "SELECT owner, state, COUNT(*) FROM job_stats WHERE ended >= ?1"
        " AND (?2 IS NULL OR owner = ?2)"
        " AND job NOT IN (SELECT id FROM jobs WHERE final = 0) GROUP BY owner, state",
        [&](const Statement& row) {
            // A state this server does not know (a newer one's) is not counted.
            if (absl::StatusOr<JobState> state = JobStateFromName(row.Column(1)); state.ok()) {
                stats.AddJobs(row.Column(0), *state, row.ColumnInt(2));
            }
        });
    if (status.ok()) {
        // Active now, whatever the window (?1 is unused: the count of parameters is the
        // highest index, so binding it is no error).
        status = read(
            "SELECT json_extract(record, '$.spec.owner') AS o, COUNT(*) FROM jobs"
            " WHERE final = 0 AND (?2 IS NULL OR o = ?2) GROUP BY o",
            [&](const Statement& row) {
                stats.AddJobs(row.Column(0), JobState::kRunning, row.ColumnInt(1));
            });
    }
    if (status.ok()) {
        status = read(
            "SELECT owner, worker, COUNT(*), SUM(samples), SUM(cpu_seconds),"
            " SUM(render_seconds) FROM task_stats WHERE finished >= ?1"
            " AND (?2 IS NULL OR owner = ?2) GROUP BY owner, worker",
            [&](const Statement& row) {
                stats.AddTasks(row.Column(0), row.Column(1), row.ColumnInt(2),
                               uint64_t(row.ColumnInt(3)),
                               {row.ColumnDouble(5), row.ColumnDouble(4)});
            });
    }
    if (status.ok()) {
        status = read(
            "SELECT worker, SUM(failures) FROM worker_failure_stats WHERE ended >= ?1"
            " AND (?2 IS NULL OR owner = ?2) GROUP BY worker",
            [&](const Statement& row) { stats.AddFailures(row.Column(0), row.ColumnInt(1)); });
    }
    if (!status.ok()) return status;
    return std::move(stats).Take(query.since);
}

absl::Status SqliteJobStore::Migrate(sqlite3* db, int64_t version) {
    // Version 0 to 1: the columns, filled from the records. Either to 2: the records rewritten
    // in the StoredJob form. Any to 3: task_results gains its history column (when an earlier
    // version made the table). In one transaction, so that a failure leaves the old version to
    // try again. To 4: the history tables, made by Open as in a new store.
    if (absl::Status s = Exec(db, "BEGIN IMMEDIATE"); !s.ok()) return s;
    absl::Status status;
    bool has_results = false;
    {
        Statement results(
            db, "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'task_results'");
        has_results = results.Step();
        status = results.status();
    }
    if (status.ok() && has_results && version < 3) {
        status = Exec(db, "ALTER TABLE task_results ADD COLUMN history TEXT NOT NULL DEFAULT ''");
    }
    if (status.ok() && version == 0) {
        status = Exec(db,
                      "DROP INDEX IF EXISTS jobs_by_request;"
                      "ALTER TABLE jobs ADD COLUMN request_id TEXT NOT NULL DEFAULT '';"
                      "ALTER TABLE jobs ADD COLUMN finished INTEGER;");
    }
    std::vector<Write> rewrites;
    if (status.ok() && version < 2) {
        Statement all(db, "SELECT id, record FROM jobs");
        while (status.ok() && all.Step()) {
            absl::StatusOr<JobRecord> job = DecodeLegacy(all.Column(0), all.Column(1));
            if (job.ok()) rewrites.push_back(PutOf(*job));
            status = job.status();
        }
        if (status.ok()) status = all.status();
    }
    for (size_t i = 0; i < rewrites.size() && status.ok(); ++i) {
        const Write& w = rewrites[i];
        Statement update(
            db, "UPDATE jobs SET record = ?2, request_id = ?3, finished = ?4 WHERE id = ?1");
        update.Bind(1, w.job_id).Bind(2, w.record).Bind(3, w.request_id).Bind(4, w.finished_us);
        update.Step();
        status = update.status();
    }
    if (status.ok()) status = Exec(db, "COMMIT");
    if (!status.ok()) {
        Exec(db, "ROLLBACK").IgnoreError();
        return absl::Status(status.code(),
                            absl::StrCat("upgrading the job store: ", status.message()));
    }
    NamedLogger("store")->info("job store upgraded from version {} to {}: {} rewritten", version,
                               kSchemaVersion, Plural(int64_t(rewrites.size()), "job"));
    return absl::OkStatus();
}

absl::Status SqliteJobStore::Health() const {
    {
        std::lock_guard<std::mutex> lock(queue_mutex_);
        if (!last_commit_.ok()) return last_commit_;
    }
    std::lock_guard<std::mutex> lock(read_mutex_);
    Statement read(read_db_, "SELECT COUNT(*) FROM jobs WHERE seq < 0");
    read.Step();
    return read.status();
}

absl::StatusOr<std::map<JobState, int64_t>> SqliteJobStore::CountEnded() const {
    std::lock_guard<std::mutex> lock(read_mutex_);
    Statement count(read_db_,
                    "SELECT json_extract(record, '$.state'), COUNT(*) FROM jobs WHERE final = 1"
                    " GROUP BY 1");
    std::map<JobState, int64_t> counts;
    while (count.Step()) {
        absl::StatusOr<JobState> state = JobStateFromName(count.Column(0));
        if (!state.ok()) return state.status();
        counts[*state] = count.ColumnInt(1);
    }
    if (!count.status().ok()) return count.status();
    return counts;
}

absl::StatusOr<JobRecord> SqliteJobStore::DecodeCached(std::string_view id,
                                                       std::string_view record) const {
    const size_t hash = std::hash<std::string_view>{}(record);
    if (auto it = decoded_.find(std::string(id));
        it != decoded_.end() && it->second.first == hash) {
        return it->second.second;
    }
    absl::StatusOr<JobRecord> job = Decode(id, record);
    if (!job.ok()) return job;
    if (decoded_.size() >= kDecodedCacheSize) decoded_.clear();
    decoded_.insert_or_assign(std::string(id), std::make_pair(hash, *job));
    return job;
}

absl::StatusOr<JobRecord> SqliteJobStore::Get(const std::string& id) const {
    std::lock_guard<std::mutex> lock(read_mutex_);
    Statement get(read_db_, "SELECT record FROM jobs WHERE id = ?1");
    if (get.Bind(1, id).Step()) return DecodeCached(id, get.Column(0));
    if (!get.status().ok()) return get.status();
    return absl::NotFoundError("no job " + id);
}

absl::StatusOr<std::vector<JobRecord>> SqliteJobStore::List(const JobQuery& query) const {
    std::lock_guard<std::mutex> lock(read_mutex_);
    std::vector<JobRecord> jobs;
    Statement list(read_db_,
                   "SELECT id, record FROM jobs WHERE seq < ?1"
                   " AND (?2 IS NULL OR (final = 1 AND finished < ?2))"
                   // The owner is read from the record rather than a column of its own: a
                   // submitter's list scans the newest jobs until its page is full, and old
                   // stores need no migration.
                   " AND (?4 IS NULL OR json_extract(record, '$.spec.owner') = ?4)"
                   " ORDER BY seq DESC LIMIT ?3");
    list.Bind(
        1, query.before_seq == 0 ? std::numeric_limits<int64_t>::max() : int64_t(query.before_seq));
    list.Bind(2, query.ended_before == absl::InfinitePast()
                     ? std::nullopt
                     : std::optional<int64_t>(absl::ToUnixMicros(query.ended_before)));
    list.Bind(3, query.limit == 0 ? int64_t(-1) : int64_t(query.limit));
    if (query.owner) list.Bind(4, *query.owner);
    while (list.Step()) {
        absl::StatusOr<JobRecord> job = DecodeCached(list.Column(0), list.Column(1));
        if (!job.ok()) return job.status();
        jobs.push_back(std::move(*job));
    }
    if (!list.status().ok()) return list.status();
    return jobs;
}

absl::StatusOr<std::optional<std::string>> SqliteJobStore::FindRequest(
    const std::string& request_id) const {
    if (request_id.empty()) return std::nullopt;
    std::lock_guard<std::mutex> lock(read_mutex_);
    Statement find(read_db_, "SELECT id FROM jobs WHERE request_id = ?1");
    if (find.Bind(1, request_id).Step()) return std::string(find.Column(0));
    if (!find.status().ok()) return find.status();
    return std::nullopt;
}

absl::StatusOr<std::map<int, JobStore::RecordedTask>> SqliteJobStore::TaskResults(
    const std::string& id) const {
    std::lock_guard<std::mutex> lock(read_mutex_);
    std::map<int, RecordedTask> results;
    // rowid grows with each write (INSERT OR REPLACE gives a replaced row a new one).
    Statement get(read_db_, "SELECT task, sums, history, rowid FROM task_results WHERE job = ?1");
    get.Bind(1, id);
    while (get.Step()) {
        const int task = int(get.ColumnInt(0));
        RecordedTask& recorded = results[task];
        recorded.result = std::string(get.Column(1));
        recorded.order = get.ColumnInt(3);
        // The history is only shown (`lightfarm tasks`): a damaged one costs the display, not
        // the result.
        absl::StatusOr<TaskHistory> history = DecodeTaskHistory(get.Column(2));
        if (history.ok()) {
            recorded.history = std::move(*history);
        } else {
            NamedLogger("store")->warn("job={} task={}: {}", id, task,
                                       std::string(history.status().message()));
        }
    }
    if (!get.status().ok()) return get.status();
    return results;
}

}  // namespace lf
