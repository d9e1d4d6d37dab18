// The few SQLite calls the server's stores share: a prepared statement that keeps its first
// error, and errors that name the database file and say when the disk is full.
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <optional>
#include <string_view>

#include "absl/status/status.h"

namespace lf {

// The connection's last error, prefixed with the database file's name. A full disk says so in its
// code (ResourceExhausted), so that the client's message is plain; a constraint broken is
// AlreadyExists; anything else is the server's problem (Internal).
absl::Status SqliteError(sqlite3* db);

// Runs statements that return no rows.
absl::Status Exec(sqlite3* db, const char* sql);

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
    Statement& Bind(int i, std::optional<int64_t> value) {
        if (value) return Bind(i, *value);
        if (rc_ == SQLITE_OK) rc_ = sqlite3_bind_null(stmt_, i);
        return *this;
    }
    Statement& BindDouble(int i, double value) {
        if (rc_ == SQLITE_OK) rc_ = sqlite3_bind_double(stmt_, i, value);
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
    // For the next row's bindings: the statement runs again, its bindings kept until rebound.
    void Reset() { sqlite3_reset(stmt_); }
    absl::Status status() const {
        if (rc_ == SQLITE_OK || rc_ == SQLITE_ROW) return absl::OkStatus();
        return SqliteError(db_);
    }
    std::string_view Column(int i) const {
        const void* data = sqlite3_column_blob(stmt_, i);
        return {static_cast<const char*>(data), size_t(sqlite3_column_bytes(stmt_, i))};
    }
    int64_t ColumnInt(int i) const { return sqlite3_column_int64(stmt_, i); }
    double ColumnDouble(int i) const { return sqlite3_column_double(stmt_, i); }
    bool IsNull(int i) const { return sqlite3_column_type(stmt_, i) == SQLITE_NULL; }

  private:
    sqlite3* db_;
    sqlite3_stmt* stmt_ = nullptr;
    int rc_;
};

}  // namespace lf
