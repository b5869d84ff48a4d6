// The study store on SQLite: a thin layer over the SQLite C API.

#include <sqlite3.h>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "sql_connection.hpp"

namespace hattr::session::detail {
namespace {

/// An SQLite failure as hattr reports it, naming the file: a damaged file (corrupt pages, not
/// a database, a table or column gone) is bad input (InputError, exit 2); anything else (a
/// full disk, a read-only file) is a runtime failure.
[[noreturn]] void throwSqlite(sqlite3* db, int rc, std::string_view doing) {
  const char* name = sqlite3_db_filename(db, "main");
  const std::string file = name && *name ? name : "study database";
  const int primary = rc & 0xff;
  if (primary == SQLITE_CORRUPT || primary == SQLITE_NOTADB || (primary == SQLITE_ERROR && doing == "prepare")) {
    // A statement of this build that does not prepare: a table or column is gone.
    throw InputError(fmt::format("{}: the study database is damaged: {}", file, sqlite3_errmsg(db)));
  }
  throw Error(fmt::format("{}: {}: {}", file, doing, sqlite3_errmsg(db)));
}

class SqliteStatement final : public SqlStatement {
 public:
  SqliteStatement(sqlite3* db, std::string_view sql) : db_(db) {
    const int rc = sqlite3_prepare_v2(db, sql.data(), static_cast<int>(sql.size()), &stmt_, nullptr);
    if (rc != SQLITE_OK) throwSqlite(db, rc, "prepare");
  }
  ~SqliteStatement() override { sqlite3_finalize(stmt_); }
  SqliteStatement(const SqliteStatement&) = delete;
  SqliteStatement& operator=(const SqliteStatement&) = delete;

  SqlStatement& bind(int i, std::int64_t v) override { return check(sqlite3_bind_int64(stmt_, i, v)); }
  SqlStatement& bind(int i, std::string_view v) override {
    return check(sqlite3_bind_text(stmt_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT));
  }
  SqlStatement& bindNull(int i) override { return check(sqlite3_bind_null(stmt_, i)); }
  SqlStatement& bindBlob(int i, std::string_view v) override {
    return check(sqlite3_bind_blob64(stmt_, i, v.data(), v.size(), SQLITE_TRANSIENT));
  }
  bool step() override {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) {
      changes_ = sqlite3_changes64(db_);
      return false;
    }
    throwSqlite(db_, rc, "step");
  }
  [[nodiscard]] std::int64_t changes() const override { return changes_; }
  [[nodiscard]] std::int64_t integer(int col) const override { return sqlite3_column_int64(stmt_, col); }
  [[nodiscard]] bool isNull(int col) const override { return sqlite3_column_type(stmt_, col) == SQLITE_NULL; }
  [[nodiscard]] std::string_view textView(int col) const override {
    const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, col));
    return p ? std::string_view(p, static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col))) : std::string_view();
  }
  [[nodiscard]] std::string_view blob(int col) const override {
    const auto* p = static_cast<const char*>(sqlite3_column_blob(stmt_, col));
    return {p, static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col))};
  }

 private:
  SqlStatement& check(int rc) {
    if (rc != SQLITE_OK) throw Error(fmt::format("study database: bind failed: {}", sqlite3_errmsg(db_)));
    return *this;
  }
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
  std::int64_t changes_ = 0;
};

class SqliteConnection final : public SqlConnection {
 public:
  SqliteConnection(sqlite3* db, std::string location) : db_(db), location_(std::move(location)) {}
  ~SqliteConnection() override { sqlite3_close(db_); }
  SqliteConnection(const SqliteConnection&) = delete;
  SqliteConnection& operator=(const SqliteConnection&) = delete;

  [[nodiscard]] SqlDialect dialect() const override { return SqlDialect::kSqlite; }
  [[nodiscard]] const std::string& location() const override { return location_; }
  [[nodiscard]] std::unique_ptr<SqlStatement> prepare(std::string_view sql) override {
    return std::make_unique<SqliteStatement>(db_, sql);
  }
  void exec(std::string_view sql) override {
    const int rc = sqlite3_exec(db_, std::string(sql).c_str(), nullptr, nullptr, nullptr);
    if (rc != SQLITE_OK) throwSqlite(db_, rc, "exec");
  }
  [[nodiscard]] sqlite3* handle() const noexcept { return db_; }

 protected:
  void beginWrite() override { exec("BEGIN IMMEDIATE"); }
  void commitWrite() override { exec("COMMIT"); }
  void rollbackWrite() noexcept override { sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr); }

 private:
  sqlite3* db_;
  std::string location_;
};

}  // namespace

std::unique_ptr<SqlConnection> makeSqliteConnection(sqlite3* db, std::string location) {
  return std::make_unique<SqliteConnection>(db, std::move(location));
}

sqlite3* sqliteHandle(SqlConnection& db) {
  HATTR_DEMAND(db.dialect() == SqlDialect::kSqlite, "an SQLite handle asked of another engine's connection");
  return static_cast<SqliteConnection&>(db).handle();
}

sqlite3* openSqliteFile(const std::filesystem::path& file, int flags, std::string_view what) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(file.c_str(), &db, flags, nullptr) != SQLITE_OK) {
    const std::string message = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    throw InputError(fmt::format("{}: cannot open {}: {}", file.string(), what, message));
  }
  sqlite3_busy_timeout(db, 5000);
  return db;
}

}  // namespace hattr::session::detail
