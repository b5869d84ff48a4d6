// The study store on PostgreSQL: a thin layer over libpq. Statements run with their
// parameters apart from the SQL (PQexecParams) and their rows come back in binary.

#include <libpq-fe.h>

#include <cstring>
#include <memory>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "sql_connection.hpp"

namespace hattr::session::detail {
namespace {

// PostgreSQL's type ids (pg_type.h, fixed since 7.x) of the columns hattr reads and writes.
constexpr Oid kBoolOid = 16, kByteaOid = 17, kInt8Oid = 20, kInt2Oid = 21, kInt4Oid = 23, kTextOid = 25;

/// An error of the server, naming the study: a table or column that is not there means the
/// database is not a (whole) hattr study: bad input.
[[noreturn]] void throwPostgres(const std::string& location, const PGresult* result, PGconn* conn,
                                std::string_view doing) {
  const char* state = result ? PQresultErrorField(result, PG_DIAG_SQLSTATE) : nullptr;
  // The server's primary message (its DETAIL may quote a whole row, sample blocks included).
  const char* primary = result ? PQresultErrorField(result, PG_DIAG_MESSAGE_PRIMARY) : nullptr;
  std::string message = primary ? primary : result ? PQresultErrorMessage(result) : PQerrorMessage(conn);
  while (!message.empty() && (message.back() == '\n' || message.back() == ' ')) message.pop_back();
  const std::string_view code = state ? state : "";
  if (code == "42P01" || code == "42703") {  // undefined table, undefined column
    throw InputError(fmt::format("{}: not a hattr study database, or a damaged one: {}", location, message));
  }
  throw Error(fmt::format("{}: {}: {}", location, doing, message));
}

/// `?` placeholders numbered as PostgreSQL's `$1`, `$2`... (hattr's SQL has no `?` in literals).
std::string numberPlaceholders(std::string_view sql) {
  std::string out;
  out.reserve(sql.size() + 16);
  int n = 0;
  for (const char c : sql) {
    if (c == '?') {
      out += fmt::format("${}", ++n);
    } else {
      out += c;
    }
  }
  return out;
}

/// A binary column's integer: network byte order, `bytes` wide, two's complement.
std::int64_t bigEndian(const char* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | static_cast<unsigned char>(p[i]);
  const int unused = 64 - 8 * bytes;
  return unused == 0 ? static_cast<std::int64_t>(v) : static_cast<std::int64_t>(v << unused) >> unused;
}

class PostgresStatement final : public SqlStatement {
 public:
  PostgresStatement(PGconn* conn, const std::string& location, std::string_view sql)
      : conn_(conn), location_(location), sql_(numberPlaceholders(sql)) {}
  ~PostgresStatement() override { PQclear(result_); }
  PostgresStatement(const PostgresStatement&) = delete;
  PostgresStatement& operator=(const PostgresStatement&) = delete;

  SqlStatement& bind(int i, std::int64_t v) override { return set(i, fmt::format("{}", v), kInt8Oid, 0); }
  SqlStatement& bind(int i, std::string_view v) override { return set(i, std::string(v), kTextOid, 0); }
  SqlStatement& bindNull(int i) override {
    set(i, {}, 0, 0);
    params_[static_cast<std::size_t>(i - 1)].null = true;
    return *this;
  }
  SqlStatement& bindBlob(int i, std::string_view v) override { return set(i, std::string(v), kByteaOid, 1); }

  bool step() override {
    if (!result_) execute();
    return ++row_ < PQntuples(result_);
  }
  [[nodiscard]] std::int64_t changes() const override {
    const char* n = result_ ? PQcmdTuples(result_) : "";
    return *n ? std::stoll(n) : 0;
  }
  [[nodiscard]] std::int64_t integer(int col) const override {
    if (isNull(col)) return 0;
    const char* p = PQgetvalue(result_, row_, col);
    switch (PQftype(result_, col)) {
      case kInt8Oid: return bigEndian(p, 8);
      case kInt4Oid: return bigEndian(p, 4);
      case kInt2Oid: return bigEndian(p, 2);
      case kBoolOid: return *p != 0 ? 1 : 0;
      default:
        throw InvariantError(fmt::format("{}: column {} read as an integer has type id {}", location_, col,
                                         PQftype(result_, col)));
    }
  }
  [[nodiscard]] bool isNull(int col) const override { return PQgetisnull(result_, row_, col) != 0; }
  [[nodiscard]] std::string_view textView(int col) const override { return blob(col); }
  [[nodiscard]] std::string_view blob(int col) const override {
    return {PQgetvalue(result_, row_, col), static_cast<std::size_t>(PQgetlength(result_, row_, col))};
  }

 private:
  struct Param {
    std::string value;
    Oid type = 0;
    int format = 0;
    bool null = false;
  };
  SqlStatement& set(int i, std::string value, Oid type, int format) {
    HATTR_DEMAND(i >= 1 && !result_, "parameter {} bound out of place", i);
    if (params_.size() < static_cast<std::size_t>(i)) params_.resize(static_cast<std::size_t>(i));
    params_[static_cast<std::size_t>(i - 1)] = {std::move(value), type, format, false};
    return *this;
  }
  void execute() {
    std::vector<const char*> values;
    std::vector<int> lengths, formats;
    std::vector<Oid> types;
    for (const Param& p : params_) {
      values.push_back(p.null ? nullptr : p.value.data());
      lengths.push_back(static_cast<int>(p.value.size()));
      formats.push_back(p.format);
      types.push_back(p.type);
    }
    result_ = PQexecParams(conn_, sql_.c_str(), static_cast<int>(params_.size()), types.data(), values.data(),
                           lengths.data(), formats.data(), /*resultFormat binary*/ 1);
    const ExecStatusType status = PQresultStatus(result_);
    if (status != PGRES_TUPLES_OK && status != PGRES_COMMAND_OK) throwPostgres(location_, result_, conn_, "query");
  }

  PGconn* conn_;
  const std::string& location_;
  std::string sql_;
  std::vector<Param> params_;
  PGresult* result_ = nullptr;
  int row_ = -1;
};

class PostgresConnection final : public SqlConnection {
 public:
  PostgresConnection(PGconn* conn, std::string location) : conn_(conn), location_(std::move(location)) {}
  ~PostgresConnection() override { PQfinish(conn_); }
  PostgresConnection(const PostgresConnection&) = delete;
  PostgresConnection& operator=(const PostgresConnection&) = delete;

  [[nodiscard]] SqlDialect dialect() const override { return SqlDialect::kPostgres; }
  [[nodiscard]] const std::string& location() const override { return location_; }
  [[nodiscard]] std::unique_ptr<SqlStatement> prepare(std::string_view sql) override {
    return std::make_unique<PostgresStatement>(conn_, location_, sql);
  }
  void exec(std::string_view sql) override {
    PGresult* result = PQexec(conn_, std::string(sql).c_str());
    const ExecStatusType status = PQresultStatus(result);
    if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK) {
      const std::unique_ptr<PGresult, decltype(&PQclear)> owned(result, &PQclear);
      throwPostgres(location_, result, conn_, "exec");
    }
    PQclear(result);
  }

 protected:
  void beginWrite() override { exec("BEGIN"); }
  void commitWrite() override {
    // COMMIT of a transaction a failed statement aborted "succeeds" as a ROLLBACK: not here.
    const std::unique_ptr<PGresult, decltype(&PQclear)> result(PQexec(conn_, "COMMIT"), &PQclear);
    if (PQresultStatus(result.get()) != PGRES_COMMAND_OK) throwPostgres(location_, result.get(), conn_, "commit");
    if (std::string_view(PQcmdStatus(result.get())) != "COMMIT") {
      throw Error(fmt::format("{}: commit: the server rolled the transaction back (a statement in it had failed)",
                              location_));
    }
  }
  void rollbackWrite() noexcept override { PQclear(PQexec(conn_, "ROLLBACK")); }

 private:
  PGconn* conn_;
  std::string location_;
};

void ignoreNotice(void*, const char*) {}

/// An address as messages show it: a password in it (user:secret@, password=secret) masked.
std::string maskPassword(std::string_view location) {
  std::string out(location);
  const auto scheme = out.find("://");
  if (scheme != std::string::npos) {
    const auto start = scheme + 3;
    const auto at = out.find('@', start);
    const auto colon = out.find(':', start);
    if (at != std::string::npos && colon != std::string::npos && colon < at) out.replace(colon + 1, at - colon - 1, "***");
  }
  for (auto p = out.find("password="); p != std::string::npos; p = out.find("password=", p + 1)) {
    const auto value = p + 9;
    const auto end = out.find('&', value);
    out.replace(value, (end == std::string::npos ? out.size() : end) - value, "***");
  }
  return out;
}

/// Whether an address may hold a password (user information, or a password parameter).
bool mayHoldPassword(std::string_view location) {
  return location.find('@') != std::string_view::npos || location.find("password") != std::string_view::npos;
}

}  // namespace

bool isPostgresLocation(std::string_view location) {
  return location.starts_with("postgresql://") || location.starts_with("postgres://");
}

std::unique_ptr<SqlConnection> connectPostgres(const std::string& location) {
  // The address is checked before any connection: well formed, and without a password.
  char* error = nullptr;
  PQconninfoOption* options = PQconninfoParse(location.c_str(), &error);
  if (!options) {
    std::string message = error ? error : "out of memory";
    PQfreemem(error);
    while (!message.empty() && message.back() == '\n') message.pop_back();
    // libpq's reason may quote any part of the address, a password too: then it is not shown.
    if (mayHoldPassword(location)) message = "(its reason is not shown: it may quote a password)";
    throw InputError(fmt::format("--db {}: expected a PostgreSQL address (postgresql://[user@][host][:port]/database"
                                 "[?param=value...]), got one libpq refuses: {}", maskPassword(location), message));
  }
  bool has_password = false;
  for (const PQconninfoOption* o = options; o->keyword; ++o) {
    has_password |= std::strcmp(o->keyword, "password") == 0 && o->val && *o->val;
  }
  PQconninfoFree(options);
  HATTR_THROW_UNLESS(!has_password, "--db: the PostgreSQL address carries a password; expected none: a password on "
                     "the command line is seen by every user of this machine and lands in logs. Put it in libpq's "
                     "password file (~/.pgpass or PGPASSFILE), a service file (PGSERVICEFILE, with "
                     "postgresql://...?service=NAME) or the PGPASSWORD environment variable");
  // hattr's defaults first, the address after (its own settings win): give up connecting
  // after 10 s, and notice a server gone silent (TCP keepalives, unacknowledged data for 30 s).
  const char* keywords[] = {"connect_timeout", "keepalives", "keepalives_idle", "keepalives_interval",
                            "keepalives_count", "tcp_user_timeout", "dbname", nullptr};
  const char* values[] = {"10", "1", "10", "5", "3", "30000", location.c_str(), nullptr};
  PGconn* conn = PQconnectdbParams(keywords, values, /*expand_dbname*/ 1);
  const std::string shown = maskPassword(location);
  if (PQstatus(conn) != CONNECTION_OK) {
    std::string message = conn ? PQerrorMessage(conn) : "out of memory";
    PQfinish(conn);
    while (!message.empty() && message.back() == '\n') message.pop_back();
    throw Error(fmt::format("{}: cannot connect to the study's PostgreSQL server: {}", shown, message));
  }
  PQsetNoticeProcessor(conn, ignoreNotice, nullptr);
  return std::make_unique<PostgresConnection>(conn, shown);
}

}  // namespace hattr::session::detail
