#include "hattr/session/study_export.hpp"

#include <unistd.h>

#include <fstream>
#include <sstream>
#include <vector>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/session/learner.hpp"

namespace hattr::session {
namespace {

/// trials.csv: each trial's plan and status, then (since designs) its place in the design.
constexpr std::string_view kTrialsHeaderV1 =
    "id,subject,sequence,mode,phase,trial,show_reference,guidance,status,attempts,interruptions,started_utc,ended_utc,"
    "samples,file";
constexpr std::string_view kTrialsHeader =
    "id,subject,sequence,mode,phase,trial,show_reference,guidance,status,attempts,interruptions,started_utc,ended_utc,"
    "samples,file,skill,group,session,day,block";

/// A name that becomes a path component of the export. A study stored before names were
/// checked can hold any ("P 01" is fine); the writer refuses what would leave its folder.
const std::string& checkedName(const std::string& name, std::string_view what) {
  HATTR_THROW_UNLESS(staysInFolder(name),
                     "study export: {} \"{}\": would not stay inside the export folder ('/', \".\", \"..\" or "
                     "empty); not written",
                     what, textExcerpt(name));
  return name;
}

}  // namespace

std::string trialFileName(const TrialPlan& p) {
  (void)checkedName(p.subject, "subject id");
  return fmt::format("trials/{}/{:03}_{}_{}_{:02}.csv", p.subject, p.sequence, guidance::modeName(p.mode), p.phase,
                     p.index);
}

namespace {

/// exportStudy's files, written into `out` (created).
std::size_t writeExport(const StudyDatabase& db, StudyDefinition study, const std::filesystem::path& out) {
  namespace fs = std::filesystem;
  fs::create_directories(out / "experts");
  // The definition, with the experts pointing into the export.
  for (auto& [skill, path] : study.experts) {
    io::writeProfileCsv(db.expert(skill), out / "experts" / (skill + ".csv"));
    path = fs::path("experts") / (skill + ".csv");
  }
  study.named_experts.clear();  // an expert named by its glyph is a file in the export too
  hattr::writeFileAtomically(out / "study.json", studyToJson(study).dump(2) + "\n");

  // The trials table and a profile per completed trial.
  std::string table = std::string(kTrialsHeader) + "\n";
  std::size_t written = 0;
  for (const TrialRecord& t : db.trials()) {
    std::string file;
    if (t.status == TrialStatus::kCompleted) {
      file = trialFileName(t.plan);
      fs::create_directories((out / file).parent_path());
      io::writeProfileCsv(db.trialProfile(t.id), out / file);
      ++written;
    }
    table += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", t.id, t.plan.subject,
                         t.plan.sequence, guidance::modeName(t.plan.mode), t.plan.phase, t.plan.index,
                         t.plan.view.show_reference ? 1 : 0, t.plan.view.guidance ? 1 : 0, trialStatusName(t.status),
                         t.attempts, t.interruptions, t.started_utc, t.ended_utc, t.sample_count, file, t.plan.skill,
                         t.plan.group, t.plan.session + 1, t.plan.day, t.plan.block + 1);
  }
  hattr::writeFileAtomically(out / "trials.csv", table);
  return written;
}

}  // namespace

std::size_t exportStudy(const StudyDatabase& db, const std::filesystem::path& out, const ExportOptions& options) {
  namespace fs = std::filesystem;
  HATTR_THROW_UNLESS(!fs::exists(out) || (fs::is_directory(out) && fs::is_empty(out)),
                     "{}: exists and is not an empty folder; choose a new folder", out.string());

  // Every name checked before anything is written.
  StudyDefinition study = db.study();
  if (!options.identified) pseudonymize(study);  // learners' names and notes stay in the database
  for (const auto& [skill, path] : study.experts) (void)checkedName(skill, "skill");
  for (const SubjectRecord& s : db.subjects()) (void)checkedName(s.id, "subject id");

  // All or nothing: written into a hidden folder inside `out` and moved into place when whole,
  // so a damaged trial or a full disk leaves no half export (and `out` as it was: absent, or
  // an empty folder, a link to one or a mount point).
  const bool existed = fs::exists(out);
  fs::create_directories(out);
  const fs::path building = out / fmt::format(".exporting-{}", ::getpid());
  std::size_t written = 0;
  try {
    written = writeExport(db, study, building);
    std::vector<fs::path> parts;  // listed first: the folder is not changed while it is read
    for (const auto& entry : fs::directory_iterator(building)) parts.push_back(entry.path());
    for (const auto& part : parts) fs::rename(part, out / part.filename());
    fs::remove(building);
  } catch (...) {
    std::error_code ignored;
    fs::remove_all(building, ignored);
    if (!existed) fs::remove(out, ignored);
    throw;
  }
  return written;
}

std::size_t importStudy(const std::filesystem::path& dir, const std::filesystem::path& db_file) {
  // All or nothing: the database appears only once every trial is in (StudyDatabase::create).
  std::size_t imported = 0;
  (void)StudyDatabase::create(db_file, loadStudy(dir / "study.json"), [&](StudyDatabase& db) {
    std::map<std::pair<std::string, int>, std::int64_t> ids;
    for (const TrialRecord& t : db.trials()) ids[{t.plan.subject, t.plan.sequence}] = t.id;
    std::map<std::int64_t, int> listed_at;  // trial id -> the table line that listed it

    // Every completed trial in trials.csv, its profile from its file inside the export.
    const auto table_file = dir / "trials.csv";
    std::ifstream in(table_file);
    HATTR_THROW_UNLESS(in.good(), "{}: cannot open for reading", table_file.string());
    std::string line;
    std::getline(in, line);
    // An export written before designs has the first 15 columns only; the plan comes from study.json.
    HATTR_THROW_UNLESS(line == kTrialsHeader || line == kTrialsHeaderV1, "{}:1: expected the header \"{}\", got \"{}\"",
                       table_file.string(), kTrialsHeader, textExcerpt(line));
    const std::size_t columns = line == kTrialsHeader ? 20 : 15;
    for (int number = 2; std::getline(in, line); ++number) {
      std::vector<std::string> fields;
      std::stringstream split(line);
      for (std::string f; std::getline(split, f, ',');) fields.push_back(f);
      if (line.ends_with(',')) fields.emplace_back();
      HATTR_THROW_UNLESS(fields.size() == columns, "{}:{}: expected {} fields, got {}", table_file.string(), number,
                         columns, fields.size());
      if (fields[8] != "completed") continue;
      int sequence = 0;
      try {
        sequence = std::stoi(fields[2]);
      } catch (const std::exception&) {
        throw InputError(fmt::format("{}:{}: sequence: expected an integer, got \"{}\"", table_file.string(), number,
                                     textExcerpt(fields[2])));
      }
      const auto id = ids.find({fields[1], sequence});
      HATTR_THROW_UNLESS(id != ids.end(), "{}:{}: subject {} has no trial {} in the study's plan", table_file.string(),
                         number, textExcerpt(fields[1]), sequence);
      const auto [first, fresh] = listed_at.emplace(id->second, number);
      HATTR_THROW_UNLESS(fresh, "{}:{}: subject {} trial {} is listed twice (first on line {})", table_file.string(),
                         number, textExcerpt(fields[1]), sequence, first->second);
      const std::filesystem::path file(fields[14]);
      HATTR_THROW_UNLESS(isPlainRelativePath(file), "{}:{}: file: expected a path inside the export folder, got \"{}\"",
                         table_file.string(), number, textExcerpt(fields[14]));
      db.completeTrial(id->second, io::readProfileCsv(dir / file), "imported");
      ++imported;
    }
  });
  return imported;
}

}  // namespace hattr::session
