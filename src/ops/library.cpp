// The profile library's actions, each one call over library::ProfileLibrary.

#include "hattr/ops/library.hpp"

#include <unistd.h>

#include <cmath>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/io/table_csv.hpp"
#include "hattr/library/sources.hpp"

namespace hattr::ops {

namespace fs = std::filesystem;
using library::EntryLabels;
using library::ProfileLibrary;

nlohmann::json LibraryChange::toJson() const { return {{"library", library}, {"count", keys.size()}, {"keys", keys}}; }

namespace {

LibraryChange added(const ProfileLibrary& lib, const library::LabelledProfiles& entries) {
  LibraryChange c{lib.location(), {}};
  for (const auto& [labels, profile] : entries) c.keys.push_back(labels.key);
  return c;
}

}  // namespace

LibraryChange libraryInit(const std::string& location) { return {ProfileLibrary::create(location).location(), {}}; }

LibraryChange libraryImportSvc2004(const std::string& location, const fs::path& folder,
                                   const io::TabletCalibration& calibration) {
  ProfileLibrary lib = ProfileLibrary::open(location);
  const auto entries = library::readSvc2004Folder(folder, calibration);
  lib.add(entries);
  return added(lib, entries);
}

LibraryChange libraryAddStudy(const std::string& location, const fs::path& study) {
  ProfileLibrary lib = ProfileLibrary::open(location);
  const auto db = session::StudyDatabase::open(study, session::OpenMode::kReadOnly);
  const auto entries = library::readStudyTrials(db);
  HATTR_THROW_UNLESS(!entries.empty(), "{}: no completed trial with samples; expected a study that has run",
                     study.string());
  lib.add(entries);
  return added(lib, entries);
}

LibraryChange libraryAddProfile(const std::string& location, const fs::path& file, EntryLabels labels) {
  ProfileLibrary lib = ProfileLibrary::open(location);
  HapticProfile profile = io::readProfileCsv(file);
  if (labels.key.empty()) labels.key = fmt::format("{}/{}/{}", labels.person, labels.skill, file.stem().string());
  if (labels.device.empty()) labels.device = profile.metadata().device;
  if (labels.source.empty()) labels.source = profile.metadata().source.empty() ? file.filename().string() : profile.metadata().source;
  lib.add(labels, profile);
  return {lib.location(), {labels.key}};
}

LibraryChange libraryRemove(const std::string& location, const std::vector<std::string>& keys) {
  ProfileLibrary lib = ProfileLibrary::open(location);
  lib.remove(keys);
  return {lib.location(), keys};
}

nlohmann::json libraryEntryJson(const library::LibraryEntry& e) {
  const EntryLabels& l = e.labels;
  return {{"id", e.id},
          {"key", l.key},
          {"person", l.person},
          {"skill", l.skill},
          {"session", l.session},
          {"date", l.date},
          {"device", l.device},
          {"source", l.source},
          {"authenticity", library::authenticityName(l.authenticity)},
          {"imitator", l.imitator},
          {"mode", l.mode},
          {"added_utc", e.added_utc},
          {"samples", e.samples},
          {"duration_s", e.duration_s},
          {"rate_hz", e.rate_hz},
          {"pressure", e.raw.pressure},
          {"tilt", e.raw.tilt}};
}

LibraryChange libraryExport(const std::string& location, const library::EntryFilter& filter, const fs::path& out,
                            bool force) {
  const ProfileLibrary lib = ProfileLibrary::open(location, true);
  const auto entries = lib.list(filter);
  HATTR_THROW_UNLESS(!entries.empty(), "{}: no entry matches; nothing to export", location);
  HATTR_THROW_UNLESS(force || !fs::exists(out), "{}: already exists; expected a new folder (or --force to replace it)",
                     out.string());
  // Written beside its place, then moved there: the folder is whole or absent.
  const fs::path parent = out.parent_path().empty() ? fs::path(".") : out.parent_path();
  const fs::path building = parent / fmt::format(".{}.exporting-{}", out.filename().string(), ::getpid());
  fs::remove_all(building);
  LibraryChange change{lib.location(), {}};
  try {
    fs::create_directories(building / "profiles");
    io::Table index{{"key", "person", "skill", "session", "date", "authenticity", "imitator", "mode", "device", "source",
                     "samples", "file"},
                    {},
                    ""};
    for (std::size_t i = 0; i < entries.size(); ++i) {
      const auto& e = entries[i];
      HapticProfile p = lib.profile(e.id);
      const EntryLabels& l = e.labels;
      for (const auto& [name, value] : std::initializer_list<std::pair<const char*, const std::string*>>{
               {"library_key", &l.key}, {"library_person", &l.person}, {"library_skill", &l.skill},
               {"library_session", &l.session}, {"library_date", &l.date}, {"library_imitator", &l.imitator},
               {"library_mode", &l.mode}}) {
        if (!value->empty()) p.metadata().extra[name] = *value;
      }
      p.metadata().extra["library_authenticity"] = std::string(library::authenticityName(l.authenticity));
      const std::string file = fmt::format("profiles/{:05d}.csv", i + 1);
      io::writeProfileCsv(p, building / file);
      index.rows.push_back({io::plainCell(l.key), io::plainCell(l.person), io::plainCell(l.skill), io::plainCell(l.session),
                            l.date, std::string(library::authenticityName(l.authenticity)), io::plainCell(l.imitator),
                            io::plainCell(l.mode), io::plainCell(l.device), io::plainCell(l.source),
                            std::to_string(e.samples), file});
      change.keys.push_back(l.key);
    }
    io::writeTable(index, building / "library.csv");
    // An old folder (--force) is moved aside first and removed only once the new one is in place.
    const fs::path old = parent / fmt::format(".{}.replaced-{}", out.filename().string(), ::getpid());
    const bool replacing = fs::exists(out);
    if (replacing) fs::rename(out, old);
    try {
      fs::rename(building, out);
    } catch (...) {
      if (replacing) fs::rename(old, out);
      throw;
    }
    if (replacing) fs::remove_all(old);
  } catch (...) {
    std::error_code ignored;
    fs::remove_all(building, ignored);
    throw;
  }
  return change;
}

// ---- Verification and identification -------------------------------------------------------------

namespace {

/// The genuine entries of a person and skill (of one session if asked), with their features.
std::vector<library::FeatureSeries> referencesOf(const ProfileLibrary& lib, const std::string& person,
                                                 const std::string& skill, const std::optional<std::string>& session,
                                                 library::FeatureSet set, const library::FeatureOptions& features,
                                                 const std::string& exclude_key) {
  const auto persons = lib.persons(skill);
  HATTR_THROW_UNLESS(std::find(persons.begin(), persons.end(), person) != persons.end(),
                     "{}: no {} profiles of {}; expected one of the persons `hattr library list --skill {}` shows",
                     lib.location(), skill, person, skill);
  std::vector<library::FeatureSeries> out;
  for (const auto& e : lib.list({.person = person, .skill = skill, .session = session,
                                 .authenticity = library::Authenticity::kGenuine})) {
    if (e.labels.key == exclude_key) continue;
    const std::string where = fmt::format("{}: entry {}", lib.location(), e.labels.key);
    out.push_back(library::extractFeatures(lib.profile(e.id), features, where));
    library::requireChannels(out.back(), set, where);
  }
  return out;
}

}  // namespace

std::string thresholdSettingName(const std::string& skill, library::FeatureSet set, const library::FeatureOptions& f,
                                 library::ScoreRule rule) {
  return fmt::format("verify-threshold skill={} features={} rule={} length={} band={} normalization={} timing={}",
                     skill, set.name(), library::scoreRuleName(rule), f.length, f.band_fraction,
                     analysis::normalizationName(f.normalization), f.timing_weight);
}

nlohmann::json VerifyResult::toJson() const {
  return {{"claim", claim},         {"skill", skill},         {"features", set},
          {"references", references}, {"spread", spread},     {"score", score},
          {"threshold", threshold}, {"threshold_from", threshold_from}, {"accepted", accepted}};
}

VerifyResult libraryVerify(const std::string& location, const HapticProfile& profile, const VerifyOptions& o) {
  const ProfileLibrary lib = ProfileLibrary::open(location, true);
  VerifyResult r{o.claim, o.skill, o.set.name()};
  if (o.threshold) {
    r.threshold = *o.threshold;
    r.threshold_from = "--threshold";
  } else {
    const auto saved = lib.setting(thresholdSettingName(o.skill, o.set, o.features, o.rule));
    HATTR_THROW_UNLESS(saved.has_value(),
                       "{}: no verification threshold for {} with features {} (rule {}, length {}, band {}, timing "
                       "weight {}); expected --threshold, or one saved by `hattr library evaluate --save-thresholds` "
                       "with these options",
                       location, o.skill, o.set.name(), library::scoreRuleName(o.rule), o.features.length,
                       o.features.band_fraction, o.features.timing_weight);
    try {
      const auto j = nlohmann::json::parse(*saved);
      r.threshold = j.at("threshold").get<double>();
      r.threshold_from = j.at("from").get<std::string>();
    } catch (const nlohmann::json::exception& e) {
      throw InputError(fmt::format("{}: the saved verification threshold is damaged: {}", location, jsonLibraryMessage(e)));
    }
  }
  HATTR_THROW_UNLESS(std::isfinite(r.threshold), "threshold: expected a finite number, got {}", r.threshold);
  const auto query = library::extractFeatures(profile, o.features, "the profile");
  library::requireChannels(query, o.set, "the profile");
  const auto enrolment = library::enrol(
      o.claim, referencesOf(lib, o.claim, o.skill, o.session, o.set, o.features, o.exclude_key), o.set, o.features);
  r.references = enrolment.references.size();
  r.spread = enrolment.spread;
  r.score = library::verificationScore(query, enrolment, o.set, o.features, o.rule);
  r.accepted = r.score <= r.threshold;
  return r;
}

nlohmann::json IdentifyResult::toJson() const {
  nlohmann::json ranked_json = nlohmann::json::array();
  for (std::size_t i = 0; i < ranked.size(); ++i) {
    ranked_json.push_back({{"rank", i + 1}, {"person", ranked[i].person}, {"nearest", ranked[i].key},
                           {"distance", ranked[i].distance}});
  }
  return {{"features", set},
          {"ranked", ranked_json},
          {"search", {{"candidates", stats.candidates}, {"lb_keogh", stats.lower_bounds},
                      {"pruned_by_lb_keogh", stats.pruned_by_keogh}, {"dtw_full", stats.dtw_full},
                      {"dtw_abandoned", stats.dtw_abandoned}}}};
}

IdentifyResult libraryIdentify(const std::string& location, const HapticProfile& profile, const IdentifyOptions& o) {
  const ProfileLibrary lib = ProfileLibrary::open(location, true);
  std::vector<library::Candidate> candidates;
  for (const auto& e : lib.list({.skill = o.skill, .authenticity = library::Authenticity::kGenuine})) {
    if (e.labels.key == o.exclude_key) continue;
    const std::string where = fmt::format("{}: entry {}", location, e.labels.key);
    candidates.push_back({e.labels.person, e.labels.key, library::extractFeatures(lib.profile(e.id), o.features, where)});
  }
  HATTR_THROW_UNLESS(!candidates.empty(), "{}: no genuine {} profiles; expected a skill `hattr library list` shows",
                     location, o.skill);
  const auto query = library::extractFeatures(profile, o.features, "the profile");
  IdentifyResult r;
  r.set = o.set.name();
  if (o.brute_force) {
    r.ranked = library::identifyBruteForce(query, candidates, o.set, o.features, o.top);
    r.stats = {.candidates = candidates.size(), .dtw_full = candidates.size()};
  } else {
    r.ranked = library::identify(query, candidates, o.set, o.features, o.top, &r.stats);
  }
  return r;
}

// ---- Evaluation ----------------------------------------------------------------------------------

library::EvaluationResult libraryEvaluate(const std::string& location, library::ProtocolOptions options, bool save) {
  ProfileLibrary lib = ProfileLibrary::open(location, !save);
  if (options.development.empty() || options.evaluation.empty()) {
    const auto split = library::svc2004Protocol(lib);
    options.development = split.development;
    options.evaluation = split.evaluation;
  }
  library::EvaluationResult result = library::evaluate(lib, options);
  if (save) {
    std::vector<std::pair<std::string, std::string>> thresholds;
    for (const auto& s : result.sets) {
      const auto& dev = s.splits.front();
      thresholds.emplace_back(thresholdSettingName(options.skill, s.set, options.features, options.rule),
                              nlohmann::json{{"threshold", dev.skilled.eer_threshold},
                                             {"from", fmt::format("the {} protocol's development writers' skilled-forgery "
                                                                  "EER threshold (seed {}, saved {})",
                                                                  result.protocol, options.seed, utcNowIso8601())}}
                                  .dump());
    }
    lib.setSettings(thresholds);  // all or none
  }
  return result;
}

}  // namespace hattr::ops
