#pragma once
// The study store on PostgreSQL: its schema, and the leases by which stations share a study's
// subjects. Internal to the session module (docs/study-store.md, "Many stations").

#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>

#include "hattr/session/study_database.hpp"
#include "sql_connection.hpp"

namespace hattr::session::detail {

/// Creates the whole schema, at this build's version, in an empty database (the caller's
/// transaction). Refuses a database that already holds a hattr study or tables of its names.
void createPostgresSchema(SqlConnection& db);

/// Checks that the database holds a hattr study this build reads; throws InputError saying
/// what it holds instead. An older schema is migrated when `writable`, refused otherwise.
void checkPostgresStudy(SqlConnection& db, bool writable);

/// This machine's name (sessions and leases record it for people).
std::string hostName();

/// A new station's id: unique across hosts and restarts (random), with host and process for people.
std::string newStationId();

/// Takes `subject`'s lease for `station`, in the caller's transaction: granted when no lease is
/// there, it is this station's, or it lapsed. On a grant, the subject's trials left running
/// become interrupted and its open sessions end: their station is gone.
SubjectClaim claimLeaseIn(SqlConnection& db, const std::string& station, const std::string& subject,
                          double lease_timeout_s);
/// claimLeaseIn in a transaction of its own.
SubjectClaim claimLease(SqlConnection& db, const std::string& station, const std::string& subject,
                        double lease_timeout_s);

/// Renews a station's leases every third of the timeout on a connection of its own, until
/// destroyed. A renewal that fails (the server away) is tried again at the next one; the
/// leases lapse if the server stays away longer than the timeout.
class LeaseKeeper {
 public:
  LeaseKeeper(const std::string& location, std::string station, double lease_timeout_s);
  ~LeaseKeeper();
  LeaseKeeper(const LeaseKeeper&) = delete;
  LeaseKeeper& operator=(const LeaseKeeper&) = delete;

 private:
  void renewUntilStopped();

  std::string location_;
  std::string station_;
  double lease_timeout_s_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace hattr::session::detail
