#include "lf/server/worker_state_store.h"

#include "absl/strings/str_cat.h"
#include "lf/server/sqlite_statement.h"

namespace lf {

namespace {

absl::Status At(const std::string& path, const absl::Status& s) {
    return s.ok() ? s : absl::Status(s.code(), absl::StrCat(path, ": ", s.message()));
}

}  // namespace

absl::StatusOr<std::unique_ptr<WorkerStateStore>> WorkerStateStore::Open(const std::string& path) {
    sqlite3* db = nullptr;
    if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
        SQLITE_OK) {
        absl::Status s = absl::UnavailableError(absl::StrCat(
            path, ": cannot open the worker state store: ", db ? sqlite3_errmsg(db) : "?"));
        sqlite3_close(db);
        return s;
    }
    std::unique_ptr<WorkerStateStore> store(new WorkerStateStore(db, path));
    if (absl::Status s = Exec(db,
                              "PRAGMA journal_mode=WAL; PRAGMA busy_timeout=5000;"
                              "CREATE TABLE IF NOT EXISTS worker_controls ("
                              "  name TEXT PRIMARY KEY, control TEXT NOT NULL);");
        !s.ok()) {
        return At(path, s);
    }
    return store;
}

WorkerStateStore::~WorkerStateStore() { sqlite3_close(db_); }

absl::Status WorkerStateStore::Put(const std::string& name, WorkerControl control) {
    if (control == WorkerControl::kEnabled) {
        Statement del(db_, "DELETE FROM worker_controls WHERE name = ?");
        del.Bind(1, name).Step();
        return At(path_, del.status());
    }
    Statement put(db_, "INSERT OR REPLACE INTO worker_controls (name, control) VALUES (?, ?)");
    put.Bind(1, name).Bind(2, std::string(WorkerControlName(control))).Step();
    return At(path_, put.status());
}

absl::StatusOr<std::map<std::string, WorkerControl>> WorkerStateStore::List() {
    std::map<std::string, WorkerControl> controls;
    Statement list(db_, "SELECT name, control FROM worker_controls");
    while (list.Step()) {
        const std::string name(list.Column(0)), control(list.Column(1));
        if (control == WorkerControlName(WorkerControl::kDisabled)) {
            controls[name] = WorkerControl::kDisabled;
        } else if (control == WorkerControlName(WorkerControl::kDrain)) {
            controls[name] = WorkerControl::kDrain;
        } else {
            return absl::DataLossError(absl::StrCat(path_, ": worker \"", name,
                                                    "\" has an unknown control \"", control, "\""));
        }
    }
    if (!list.status().ok()) return At(path_, list.status());
    return controls;
}

}  // namespace lf
