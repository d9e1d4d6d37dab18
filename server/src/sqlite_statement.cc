#include "lf/server/sqlite_statement.h"

#include <string>

#include "absl/strings/str_cat.h"

namespace lf {

absl::Status SqliteError(sqlite3* db) {
    // The file's name without its folder: messages reach clients, the data folder's path must not.
    const std::string file = sqlite3_db_filename(db, "main");
    const std::string message =
        absl::StrCat(file.substr(file.rfind('/') + 1), ": ", sqlite3_errmsg(db));
    if ((sqlite3_extended_errcode(db) & 0xff) == SQLITE_FULL) {
        return absl::ResourceExhaustedError(message);
    }
    // A second job with one request id, a second token of one name: kept out by the schema.
    if ((sqlite3_extended_errcode(db) & 0xff) == SQLITE_CONSTRAINT) {
        return absl::AlreadyExistsError(message);
    }
    return absl::InternalError(message);
}

absl::Status Exec(sqlite3* db, const char* sql) {
    if (sqlite3_exec(db, sql, nullptr, nullptr, nullptr) == SQLITE_OK) return absl::OkStatus();
    return SqliteError(db);
}

}  // namespace lf
