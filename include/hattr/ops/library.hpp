#pragma once
/// The profile library's actions (`hattr library ...`, Python's hattr.Library; docs/library.md)
/// as library calls: each opens the library, does one thing all or nothing, and returns a result
/// with its toJson, as the CLI prints it with --json. Throws InputError for bad input (exit 2
/// in the CLI), the library unchanged. Not for the servo thread.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "hattr/io/tablet_import.hpp"
#include "hattr/library/evaluation.hpp"
#include "hattr/library/matching.hpp"
#include "hattr/library/profile_library.hpp"

namespace hattr::ops {

/// Entries added (or removed): the library and their keys.
struct LibraryChange {
  std::string library;
  std::vector<std::string> keys;
  [[nodiscard]] nlohmann::json toJson() const;  ///< {library, count, keys}
};

/// `hattr library init`: a new, empty library.
LibraryChange libraryInit(const std::string& library);
/// `hattr library import svc2004 FOLDER`: every signature of the folder, labelled.
LibraryChange libraryImportSvc2004(const std::string& library, const std::filesystem::path& folder,
                                   const io::TabletCalibration& calibration);
/// `hattr library add --study FILE`: a study's completed trials, with their subjects and modes.
LibraryChange libraryAddStudy(const std::string& library, const std::filesystem::path& study);
/// `hattr library add PROFILE.csv --person P --skill S ...`: one profile file. An empty key is
/// made from the person, skill and the file's name; empty device and source from its metadata.
LibraryChange libraryAddProfile(const std::string& library, const std::filesystem::path& profile,
                                library::EntryLabels labels);
/// `hattr library remove KEY...`: all or none.
LibraryChange libraryRemove(const std::string& library, const std::vector<std::string>& keys);
/// `hattr library export --out DIR`: each matching entry as a profile CSV (its labels in the
/// metadata) and DIR/library.csv indexing them; the folder is written beside and moved into
/// place, so it is whole or absent.
LibraryChange libraryExport(const std::string& library, const library::EntryFilter& filter,
                            const std::filesystem::path& out, bool force);

/// An entry's labels and summary as JSON (list and show).
nlohmann::json libraryEntryJson(const library::LibraryEntry& entry);

/// Verification of a profile against a person's enrolled genuine profiles of a skill.
struct VerifyOptions {
  std::string claim;
  std::string skill;
  std::optional<std::string> session;  ///< enrol only this session's profiles
  library::FeatureSet set;
  library::FeatureOptions features;
  library::ScoreRule rule = library::ScoreRule::kMean;
  std::optional<double> threshold;     ///< else the one an evaluation saved in the library
  std::string exclude_key;             ///< an entry left out of the enrolment (the query's own, entry:KEY)
};
struct VerifyResult {
  std::string claim, skill, set;
  std::size_t references = 0;
  double spread = 0.0;
  double score = 0.0;
  double threshold = 0.0;
  std::string threshold_from;  ///< "--threshold", or the evaluation that saved it
  bool accepted = false;
  [[nodiscard]] nlohmann::json toJson() const;
};
VerifyResult libraryVerify(const std::string& library, const HapticProfile& profile, const VerifyOptions& options);

/// Identification of a profile among the persons of a skill (every genuine entry), exactly.
struct IdentifyOptions {
  std::string skill;
  library::FeatureSet set;
  library::FeatureOptions features;
  std::size_t top = 5;
  bool brute_force = false;  ///< every distance in full (the baseline), same answer
  std::string exclude_key;   ///< an entry left out of the candidates (the query's own, entry:KEY)
};
struct IdentifyResult {
  std::vector<library::RankedPerson> ranked;
  library::SearchStats stats;
  std::string set;
  [[nodiscard]] nlohmann::json toJson() const;
};
IdentifyResult libraryIdentify(const std::string& library, const HapticProfile& profile, const IdentifyOptions& options);

/// The name under which an evaluation saves a verification threshold for these options.
std::string thresholdSettingName(const std::string& skill, library::FeatureSet set, const library::FeatureOptions& features,
                                 library::ScoreRule rule);

/// `hattr library evaluate --protocol svc2004`: the protocol on the library, and (when `save`)
/// each feature set's a-priori skilled-forgery threshold saved in it for `verify`.
library::EvaluationResult libraryEvaluate(const std::string& library, library::ProtocolOptions options, bool save);
/// (Its JSON, text and report: hattr/report/library_report.hpp.)

}  // namespace hattr::ops
