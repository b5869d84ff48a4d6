#pragma once
/// The profile library: haptic profiles kept with who wrote them, what skill, when and how, so
/// that a person's profiles can be compared, averaged into a template, verified and searched
/// (the paper's closing remarks: "a library of Haptic Profiles for various motor skills").
///
/// A library is an SQLite file (one station) or a PostgreSQL database (where the study store
/// already runs on one), on the study store's SQL layer. Every change is one transaction: a
/// crash or an error leaves the library as it was, never half-changed. Samples are stored
/// losslessly in the study store's encoding (docs/library.md). Not for the servo thread; one
/// ProfileLibrary is used from one thread at a time. Bad input (an unknown key, a duplicate, a
/// library of a newer schema) throws hattr::InputError naming the library and what was expected.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "hattr/core/haptic_profile.hpp"

namespace hattr::session::detail {
class SqlConnection;
}

namespace hattr::library {

/// The schema this build writes; a library of a newer one is refused.
inline constexpr int kLibrarySchemaVersion = 1;

/// Whether a profile is the person's own doing of the skill or someone else's imitation of it
/// (a forgery of their signature, a trainee copying them).
enum class Authenticity { kGenuine, kImitation };
std::string_view authenticityName(Authenticity a);  ///< "genuine", "imitation"
/// The authenticity with that name; throws InputError naming `where` otherwise.
Authenticity parseAuthenticity(std::string_view name, std::string_view where);

/// What a library knows of one profile.
struct EntryLabels {
  std::string key;        ///< unique in the library ("svc2004/U1S1", "study/paper/trial-12")
  std::string person;     ///< whose skill it is; for an imitation, the person imitated
  std::string skill;      ///< "signature", a character ("na"), a task
  std::string session;    ///< the recording session ("1", "2", "day-3"); "" unknown
  std::string date;       ///< ISO 8601 date of the recording; "" unknown
  std::string device;     ///< the device it was recorded on
  std::string source;     ///< where it came from ("import:svc2004 U1S1.TXT", a study)
  Authenticity authenticity = Authenticity::kGenuine;
  std::string imitator;   ///< who imitated, for an imitation; "" unknown
  std::string mode;       ///< the training mode of a study trial; "" otherwise
  friend bool operator==(const EntryLabels&, const EntryLabels&) = default;
};

/// One stored profile's labels and summary.
struct LibraryEntry {
  std::int64_t id = 0;
  EntryLabels labels;
  std::string added_utc;
  std::size_t samples = 0;
  double duration_s = 0.0;
  double rate_hz = 0.0;
  RawChannels raw;
};

/// Which entries: every field that is set must match.
struct EntryFilter {
  std::optional<std::string> person;
  std::optional<std::string> skill;
  std::optional<std::string> session;
  std::optional<Authenticity> authenticity;
  [[nodiscard]] bool matches(const EntryLabels& labels) const;
};

/// Labels checked before anything is stored: key, person and skill non-empty and printable,
/// date empty or YYYY-MM-DD, an imitator only on an imitation. Throws InputError naming `where`.
void checkLabels(const EntryLabels& labels, std::string_view where);

/// Whether `location` names a PostgreSQL library (postgresql:// or postgres://) rather than a file.
bool isDatabaseAddress(std::string_view location);

class ProfileLibrary {
 public:
  /// Makes a new, empty library: an SQLite file (refused if it exists; built beside it and
  /// moved into place, so a crash leaves no half-made library) or a postgresql:// database
  /// (refused if it already holds a library).
  static ProfileLibrary create(const std::string& location);
  /// Opens a library; refuses one that is not a library or is of a newer schema.
  static ProfileLibrary open(const std::string& location, bool read_only = false);

  ProfileLibrary(ProfileLibrary&&) noexcept;
  ProfileLibrary& operator=(ProfileLibrary&&) noexcept;
  ~ProfileLibrary();

  /// Where the library is: its file, or its postgresql:// address.
  [[nodiscard]] const std::string& location() const;

  /// Adds profiles with their labels, all or none: a key already in the library (or twice in
  /// `entries`), bad labels or an empty profile throw InputError and nothing is added. Returns
  /// the new entries' ids, in order.
  std::vector<std::int64_t> add(std::span<const std::pair<EntryLabels, HapticProfile>> entries);
  std::int64_t add(const EntryLabels& labels, const HapticProfile& profile);

  /// The entries the filter matches, ordered by person, skill, session, key.
  [[nodiscard]] std::vector<LibraryEntry> list(const EntryFilter& filter = {}) const;
  /// The entry with this key; InputError naming the key if there is none.
  [[nodiscard]] LibraryEntry entry(std::string_view key) const;
  /// An entry's profile, as it was added (sample for sample); the labels are not in it.
  [[nodiscard]] HapticProfile profile(std::int64_t id) const;
  [[nodiscard]] HapticProfile profile(std::string_view key) const;
  /// Removes entries by key, all or none: an unknown key throws InputError and nothing is removed.
  void remove(std::span<const std::string> keys);

  /// A named setting the library keeps beside its entries (a verification threshold fixed by an
  /// evaluation), or nothing. Names and values are text.
  [[nodiscard]] std::optional<std::string> setting(std::string_view name) const;
  void setSetting(std::string_view name, std::string_view value);
  /// Several settings in one transaction: all or none.
  void setSettings(std::span<const std::pair<std::string, std::string>> settings);

  /// The persons with at least one entry of the skill (any skill when empty), sorted.
  [[nodiscard]] std::vector<std::string> persons(std::string_view skill = {}) const;

 private:
  explicit ProfileLibrary(std::unique_ptr<session::detail::SqlConnection> db);
  std::unique_ptr<session::detail::SqlConnection> db_;
};

}  // namespace hattr::library
