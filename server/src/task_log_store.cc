#include "lf/server/task_log_store.h"

#include <algorithm>
#include <array>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "lf/core/log.h"
#include "lf/server/sqlite_statement.h"

namespace lf {

namespace {

// spdlog's level names (spdlog::level::to_string_view); anything else from the wire is "info".
std::string ValidLevel(const std::string& level) {
    static const std::array<const char*, 6> kLevels = {"trace",   "debug", "info",
                                                       "warning", "error", "critical"};
    for (const char* name : kLevels) {
        if (level == name) return level;
    }
    return "info";
}

std::string DroppedText(int64_t dropped) {
    return absl::StrCat("... ", dropped, " earlier lines dropped");
}

int64_t UnixMs(absl::Time t) { return t == absl::InfinitePast() ? 0 : absl::ToUnixMillis(t); }

absl::Time FromUnixMs(int64_t ms) {
    return ms == 0 ? absl::InfinitePast() : absl::FromUnixMillis(ms);
}

// Commits on Commit(), rolls back otherwise.
class Transaction {
  public:
    explicit Transaction(sqlite3* db) : db_(db), begun_(Exec(db, "BEGIN IMMEDIATE")) {}
    ~Transaction() {
        if (begun_.ok() && !committed_) Exec(db_, "ROLLBACK").IgnoreError();
    }
    const absl::Status& begun() const { return begun_; }
    absl::Status Commit() {
        absl::Status s = Exec(db_, "COMMIT");
        committed_ = s.ok();
        return s;
    }

  private:
    sqlite3* db_;
    absl::Status begun_;
    bool committed_ = false;
};

}  // namespace

absl::StatusOr<std::unique_ptr<TaskLogStore>> TaskLogStore::Open(const std::string& path,
                                                                 TaskLogLimits limits) {
    sqlite3* db = nullptr;
    if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
        SQLITE_OK) {
        absl::Status s = absl::UnavailableError(absl::StrCat(
            path, ": cannot open the task log store: ", db ? sqlite3_errmsg(db) : "?"));
        sqlite3_close(db);
        return s;
    }
    std::unique_ptr<TaskLogStore> store(new TaskLogStore(db, limits));
    // AUTOINCREMENT: a seq is never handed out twice, even after the newest lines are deleted
    // with their job, so a client following a log never skips a line.
    const absl::Status s =
        Exec(db,
             "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL; PRAGMA busy_timeout=5000;"
             "CREATE TABLE IF NOT EXISTS lines (seq INTEGER PRIMARY KEY AUTOINCREMENT,"
             "  job TEXT NOT NULL, task INTEGER NOT NULL, attempt INTEGER NOT NULL,"
             "  worker TEXT NOT NULL, unix_ms INTEGER NOT NULL, level TEXT NOT NULL,"
             "  text TEXT NOT NULL, dropped INTEGER NOT NULL DEFAULT 0);"
             "CREATE INDEX IF NOT EXISTS lines_by_job ON lines (job, seq);"
             "CREATE INDEX IF NOT EXISTS lines_by_task ON lines (job, task, seq);"
             "CREATE TABLE IF NOT EXISTS tasks (job TEXT NOT NULL, task INTEGER NOT NULL,"
             "  state TEXT NOT NULL, kind INTEGER NOT NULL, x INTEGER NOT NULL,"
             "  y INTEGER NOT NULL, width INTEGER NOT NULL, height INTEGER NOT NULL,"
             "  samples INTEGER NOT NULL, attempts INTEGER NOT NULL, failures INTEGER NOT NULL,"
             "  worker TEXT NOT NULL, leased_ms INTEGER NOT NULL, finished_ms INTEGER NOT NULL,"
             "  duration_ms INTEGER NOT NULL, last_error TEXT NOT NULL,"
             "  frames TEXT NOT NULL DEFAULT '',"
             "  render_seconds REAL NOT NULL DEFAULT 0, cpu_seconds REAL NOT NULL DEFAULT 0,"
             "  PRIMARY KEY (job, task));");
    if (!s.ok()) return absl::Status(s.code(), absl::StrCat(path, ": ", s.message()));
    // A store written before shots has no frames column (its tasks are stills': ""), one
    // written before the history (issue 30) no times (0: not measured).
    for (const auto& [column, definition] :
         {std::pair{"frames", "frames TEXT NOT NULL DEFAULT ''"},
          std::pair{"render_seconds", "render_seconds REAL NOT NULL DEFAULT 0"},
          std::pair{"cpu_seconds", "cpu_seconds REAL NOT NULL DEFAULT 0"}}) {
        bool present = false;
        {
            Statement has(db, "SELECT 1 FROM pragma_table_info('tasks') WHERE name = ?1");
            present = has.Bind(1, column).Step();
            if (!has.status().ok()) {
                return absl::Status(has.status().code(),
                                    absl::StrCat(path, ": ", has.status().message()));
            }
        }  // finalized before the table changes
        if (present) continue;
        if (absl::Status a =
                Exec(db, absl::StrCat("ALTER TABLE tasks ADD COLUMN ", definition).c_str());
            !a.ok()) {
            return absl::Status(a.code(), absl::StrCat(path, ": ", a.message()));
        }
    }
    return store;
}

TaskLogStore::~TaskLogStore() { sqlite3_close(db_); }

absl::Status TaskLogStore::Append(const std::string& job_id, int task, int attempt,
                                  const std::string& worker, std::vector<TaskLogLine> lines) {
    if (lines.empty()) return absl::OkStatus();
    // A message keeps its newest lines, as a task keeps its newest.
    int64_t cut = 0;
    if (int(lines.size()) > limits_.max_lines_per_message) {
        cut = int64_t(lines.size()) - limits_.max_lines_per_message;
        lines.erase(lines.begin(), lines.begin() + cut);
    }
    for (TaskLogLine& line : lines) {
        line.task = task;
        line.attempt = attempt;
        line.worker = worker;
        line.level = ValidLevel(line.level);
        line.text = LogSafe(line.text, limits_.max_line_bytes);
        if (line.time < absl::UnixEpoch()) line.time = absl::UnixEpoch();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    Transaction transaction(db_);
    if (!transaction.begun().ok()) return transaction.begun();
    if (cut > 0) {
        if (absl::Status s = CountDropped(job_id, task, cut, std::nullopt, lines.front());
            !s.ok()) {
            return s;
        }
    }
    Statement insert(db_,
                     "INSERT INTO lines (job, task, attempt, worker, unix_ms, level, text)"
                     " VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)");
    for (const TaskLogLine& line : lines) {
        insert.Bind(1, job_id)
            .Bind(2, int64_t(task))
            .Bind(3, int64_t(attempt))
            .Bind(4, worker)
            .Bind(5, absl::ToUnixMillis(line.time))
            .Bind(6, line.level)
            .Bind(7, line.text);
        insert.Step();
        if (!insert.status().ok()) return insert.status();
        insert.Reset();
    }
    if (absl::StatusOr<int64_t> trimmed = Trim(job_id, task); !trimmed.ok()) {
        return trimmed.status();
    }
    return transaction.Commit();
}

absl::StatusOr<int64_t> TaskLogStore::Trim(const std::string& job_id, int task) {
    // Newest first: the lines that fit are kept, the first that does not fit and every older
    // one go.
    Statement lines(db_,
                    "SELECT seq, length(text), unix_ms, attempt, worker FROM lines"
                    " WHERE job = ?1 AND task = ?2 AND dropped = 0 ORDER BY seq DESC");
    lines.Bind(1, job_id).Bind(2, int64_t(task));
    int kept = 0;
    int64_t bytes = 0;
    std::optional<int64_t> newest_dropped;
    TaskLogLine like;
    int64_t dropped = 0;
    while (lines.Step()) {
        if (newest_dropped) {
            ++dropped;
            continue;
        }
        const int64_t length = lines.ColumnInt(1);
        if (kept + 1 > limits_.max_lines_per_task || bytes + length > limits_.max_bytes_per_task) {
            newest_dropped = lines.ColumnInt(0);
            like.time = absl::FromUnixMillis(lines.ColumnInt(2));
            like.attempt = int(lines.ColumnInt(3));
            like.worker = std::string(lines.Column(4));
            ++dropped;
            continue;
        }
        ++kept;
        bytes += length;
    }
    if (!lines.status().ok()) return lines.status();
    if (!newest_dropped) return 0;
    Statement remove(db_,
                     "DELETE FROM lines WHERE job = ?1 AND task = ?2 AND dropped = 0"
                     " AND seq <= ?3");
    remove.Bind(1, job_id).Bind(2, int64_t(task)).Bind(3, *newest_dropped);
    remove.Step();
    if (!remove.status().ok()) return remove.status();
    if (absl::Status s = CountDropped(job_id, task, dropped, newest_dropped, like); !s.ok()) {
        return s;
    }
    return dropped;
}

absl::Status TaskLogStore::CountDropped(const std::string& job_id, int task, int64_t dropped,
                                        std::optional<int64_t> seq, const TaskLogLine& like) {
    Statement find(db_,
                   "SELECT seq, dropped FROM lines WHERE job = ?1 AND task = ?2"
                   " AND dropped > 0");
    find.Bind(1, job_id).Bind(2, int64_t(task));
    if (find.Step()) {
        const int64_t at = find.ColumnInt(0);
        const int64_t total = find.ColumnInt(1) + dropped;
        Statement update(db_, "UPDATE lines SET dropped = ?1, text = ?2 WHERE seq = ?3");
        update.Bind(1, total).Bind(2, DroppedText(total)).Bind(3, at);
        update.Step();
        return update.status();
    }
    if (!find.status().ok()) return find.status();
    Statement insert(db_,
                     "INSERT INTO lines (seq, job, task, attempt, worker, unix_ms, level, text,"
                     " dropped) VALUES (?1, ?2, ?3, ?4, ?5, ?6, 'warning', ?7, ?8)");
    insert.Bind(1, seq)
        .Bind(2, job_id)
        .Bind(3, int64_t(task))
        .Bind(4, int64_t(like.attempt))
        .Bind(5, like.worker)
        .Bind(6, absl::ToUnixMillis(like.time))
        .Bind(7, DroppedText(dropped))
        .Bind(8, dropped);
    insert.Step();
    return insert.status();
}

absl::StatusOr<TaskLogPage> TaskLogStore::Read(const std::string& job_id, std::optional<int> task,
                                               int64_t after_seq, int max_lines) {
    std::lock_guard<std::mutex> lock(mutex_);
    Statement select(db_,
                     "SELECT seq, task, attempt, worker, unix_ms, level, text FROM lines"
                     " WHERE job = ?1 AND seq > ?2 AND (?3 IS NULL OR task = ?3)"
                     " ORDER BY seq LIMIT ?4");
    select.Bind(1, job_id)
        .Bind(2, after_seq)
        .Bind(3, task ? std::optional<int64_t>(*task) : std::nullopt)
        .Bind(4, int64_t(max_lines));
    TaskLogPage page;
    page.next_seq = after_seq;
    while (select.Step()) {
        TaskLogLine& line = page.lines.emplace_back();
        line.seq = select.ColumnInt(0);
        line.task = int(select.ColumnInt(1));
        line.attempt = int(select.ColumnInt(2));
        line.worker = std::string(select.Column(3));
        line.time = absl::FromUnixMillis(select.ColumnInt(4));
        line.level = std::string(select.Column(5));
        line.text = std::string(select.Column(6));
        page.next_seq = line.seq;
    }
    if (!select.status().ok()) return select.status();
    return page;
}

absl::StatusOr<std::map<int, int>> TaskLogStore::LineCounts(const std::string& job_id) {
    std::lock_guard<std::mutex> lock(mutex_);
    Statement select(db_, "SELECT task, count(*) FROM lines WHERE job = ?1 GROUP BY task");
    select.Bind(1, job_id);
    std::map<int, int> counts;
    while (select.Step()) counts[int(select.ColumnInt(0))] = int(select.ColumnInt(1));
    if (!select.status().ok()) return select.status();
    return counts;
}

absl::Status TaskLogStore::RecordTasks(const std::string& job_id,
                                       const std::vector<TaskStatus>& tasks) {
    std::lock_guard<std::mutex> lock(mutex_);
    Transaction transaction(db_);
    if (!transaction.begun().ok()) return transaction.begun();
    Statement insert(db_,
                     "INSERT OR REPLACE INTO tasks (job, task, state, kind, x, y, width, height,"
                     " samples, attempts, failures, worker, leased_ms, finished_ms, duration_ms,"
                     " last_error, frames, render_seconds, cpu_seconds) VALUES (?1, ?2, ?3, ?4,"
                     " ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18, ?19)");
    for (const TaskStatus& t : tasks) {
        insert.Bind(1, job_id)
            .Bind(2, int64_t(t.index))
            .Bind(3, TaskStatusName(t.state))
            .Bind(4, int64_t(t.kind))
            .Bind(5, int64_t(t.x))
            .Bind(6, int64_t(t.y))
            .Bind(7, int64_t(t.width))
            .Bind(8, int64_t(t.height))
            .Bind(9, int64_t(t.samples))
            .Bind(10, int64_t(t.attempts))
            .Bind(11, int64_t(t.failures))
            .Bind(12, t.worker)
            .Bind(13, UnixMs(t.leased))
            .Bind(14, UnixMs(t.finished))
            .Bind(15, absl::ToInt64Milliseconds(t.duration))
            .Bind(16, t.last_error)
            .Bind(17, absl::StrJoin(t.frames, ","))
            .BindDouble(18, t.times.render_seconds)
            .BindDouble(19, t.times.cpu_seconds);
        insert.Step();
        if (!insert.status().ok()) return insert.status();
        insert.Reset();
    }
    return transaction.Commit();
}

absl::StatusOr<std::vector<TaskStatus>> TaskLogStore::Tasks(const std::string& job_id) {
    std::lock_guard<std::mutex> lock(mutex_);
    Statement select(db_,
                     "SELECT task, state, kind, x, y, width, height, samples, attempts, failures,"
                     " worker, leased_ms, finished_ms, duration_ms, last_error, frames,"
                     " render_seconds, cpu_seconds FROM tasks WHERE job = ?1 ORDER BY task");
    select.Bind(1, job_id);
    std::vector<TaskStatus> tasks;
    while (select.Step()) {
        TaskStatus& t = tasks.emplace_back();
        t.index = int(select.ColumnInt(0));
        // Recorded by this file: an unknown name is a damaged row, read as queued.
        t.state = TaskStatusFromName(select.Column(1)).value_or(TaskStatus::State::kQueued);
        const int64_t kind = select.ColumnInt(2);
        t.kind = kind >= 0 && kind <= int64_t(TaskKind::kRadiositySweep) ? TaskKind(kind)
                                                                         : TaskKind::kTile;
        t.x = int(select.ColumnInt(3));
        t.y = int(select.ColumnInt(4));
        t.width = int(select.ColumnInt(5));
        t.height = int(select.ColumnInt(6));
        t.samples = uint64_t(select.ColumnInt(7));
        t.attempts = int(select.ColumnInt(8));
        t.failures = int(select.ColumnInt(9));
        t.worker = std::string(select.Column(10));
        t.leased = FromUnixMs(select.ColumnInt(11));
        t.finished = FromUnixMs(select.ColumnInt(12));
        t.duration = absl::Milliseconds(select.ColumnInt(13));
        t.last_error = std::string(select.Column(14));
        // Written by RecordTasks: a part that is not a number is a damaged row, skipped.
        for (absl::string_view part :
             absl::StrSplit(std::string(select.Column(15)), ',', absl::SkipEmpty())) {
            int frame = 0;
            if (absl::SimpleAtoi(part, &frame)) t.frames.push_back(frame);
        }
        t.times = {select.ColumnDouble(16), select.ColumnDouble(17)};
    }
    if (!select.status().ok()) return select.status();
    return tasks;
}

absl::Status TaskLogStore::Delete(const std::vector<std::string>& job_ids) {
    std::lock_guard<std::mutex> lock(mutex_);
    Transaction transaction(db_);
    if (!transaction.begun().ok()) return transaction.begun();
    for (const char* sql :
         {"DELETE FROM lines WHERE job = ?1", "DELETE FROM tasks WHERE job = ?1"}) {
        Statement remove(db_, sql);
        for (const std::string& id : job_ids) {
            remove.Bind(1, id);
            remove.Step();
            if (!remove.status().ok()) return remove.status();
            remove.Reset();
        }
    }
    return transaction.Commit();
}

}  // namespace lf
