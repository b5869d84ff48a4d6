#include "hattr/sim/in_silico.hpp"

#include <algorithm>
#include <chrono>
#include <thread>

#include <fmt/chrono.h>
#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/report/design_analysis.hpp"
#include "hattr/report/study_report.hpp"
#include "hattr/session/study_runner.hpp"
#include "hattr/sim/expert.hpp"
#include "hattr/sim/glyph.hpp"
#include "hattr/sim/participant.hpp"

namespace hattr::sim {
namespace {

struct KeyedParameter {
  std::string_view key;
  ModelParameter TraineeModel::*member;
};

constexpr KeyedParameter kParameters[] = {
    {"fast_retention", &TraineeModel::fast_retention},
    {"fast_rate", &TraineeModel::fast_rate},
    {"slow_retention", &TraineeModel::slow_retention},
    {"slow_rate", &TraineeModel::slow_rate},
    {"weber_fraction", &TraineeModel::weber_fraction},
    {"felt_force_stiffness_N_per_m", &TraineeModel::felt_force_stiffness_N_per_m},
    {"position_noise_coefficient", &TraineeModel::position_noise_coefficient},
    {"force_noise_coefficient", &TraineeModel::force_noise_coefficient},
    {"deviation_rms_m", &TraineeModel::deviation_rms_m},
    {"force_scale", &TraineeModel::force_scale},
    {"force_offset_N", &TraineeModel::force_offset_N},
};

/// Keeps an existing file under a new name: nothing recorded is lost.
void keepAside(const std::filesystem::path& file) {
  if (!std::filesystem::exists(file)) return;
  const auto now = std::chrono::floor<std::chrono::seconds>(std::chrono::system_clock::now());
  auto kept = file;
  kept.replace_filename(fmt::format("{}-{:%Y%m%d-%H%M%S}{}", file.stem().string(), now, file.extension().string()));
  std::filesystem::rename(file, kept);
  for (const char* suffix : {"-wal", "-shm"}) {
    const std::filesystem::path side = file.string() + suffix;
    if (std::filesystem::exists(side)) std::filesystem::rename(side, kept.string() + suffix);
  }
}

}  // namespace

std::vector<std::string> modelParameterKeys() {
  std::vector<std::string> keys;
  for (const auto& p : kParameters) keys.emplace_back(p.key);
  return keys;
}

void setModelParameter(TraineeModel& model, std::string_view key, double value) {
  for (const auto& p : kParameters) {
    if (p.key != key) continue;
    ModelParameter& param = model.*(p.member);
    HATTR_THROW_UNLESS(value >= param.min && value <= param.max, "model parameter {}: expected a value in [{}, {}], got {}",
                       key, param.min, param.max, value);
    param.value = value;
    return;
  }
  throw InputError(fmt::format("model parameter \"{}\": expected one of {}", key, fmt::join(modelParameterKeys(), ", ")));
}

std::vector<session::SubjectSpec> simulatedSubjects(int count, std::uint64_t seed, const nlohmann::json& options) {
  std::vector<session::SubjectSpec> subjects;
  for (int i = 1; i <= count; ++i) {
    subjects.push_back({fmt::format("S{:02}", i), "simulated", seed * 1000 + static_cast<std::uint64_t>(i), options});
  }
  return subjects;
}

session::StudyDefinition writePaperStudy(const std::filesystem::path& dir, const InSilicoOptions& o) {
  HATTR_THROW_UNLESS(o.subjects >= 2 && o.subjects <= 1000, "subjects: expected 2 to 1000, got {}", o.subjects);
  HATTR_THROW_UNLESS(o.recall_trials >= 2 && o.training_trials >= 0, "trials: expected >= 2 recall and >= 0 training, got {} and {}",
                     o.recall_trials, o.training_trials);
  std::filesystem::create_directories(dir);
  // The expert: what they mean to write (the script), and what the pen records (the reference).
  const Glyph glyph = findGlyph(o.glyph);
  const HapticProfile script = expertScript(glyph);
  session::TrialEnvironment environment("sim://pen", render::WorldConfig{}, 1000.0);
  const HapticProfile expert = recordExpert(environment, script,
                                            {.subject = "expert", .skill = glyph.name, .source = "sim:expert"});
  io::writeProfileCsv(script, dir / "expert-script.csv", hattr::Overwrite::kReplace);
  io::writeProfileCsv(expert, dir / "expert.csv", hattr::Overwrite::kReplace);
  // The study: the paper's protocol, counterbalanced, simulated subjects.
  session::StudyDefinition study;
  study.name = fmt::format("{} in silico: three training modes{}", glyph.name, o.guidance ? "" : " (A/A: no guidance)");
  study.skill = glyph.name;
  study.experts[glyph.name] = dir / "expert.csv";
  study.modes = {guidance::TrainingMode::kBasic, guidance::TrainingMode::kPositionControl,
                 guidance::TrainingMode::kForceControl};
  study.protocol.training_trials = o.training_trials;
  study.protocol.recall_trials = o.recall_trials;
  study.protocol.training.guidance = o.guidance;
  HATTR_THROW_UNLESS(!(o.hypothesis && o.model), "in-silico study: expected a hypothesis or a model, got both");
  nlohmann::json options = {{"template", (dir / "expert-script.csv").string()}};
  if (o.hypothesis) options["hypothesis"] = std::string(hypothesisName(*o.hypothesis));
  study.subjects = simulatedSubjects(o.subjects, o.seed, options);
  session::applyPaperForm(study);
  return study;
}

InSilicoResult runInSilicoStudy(const InSilicoOptions& o) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::absolute(o.out_dir);
  const session::StudyDefinition study = writePaperStudy(dir, o);
  hattr::writeFileAtomically(dir / "study.json", session::studyToJson(study).dump(2) + "\n", hattr::Overwrite::kReplace);
  keepAside(dir / "study.sqlite");
  { (void)session::StudyDatabase::create(dir / "study.sqlite", study); }

  // Run it.
  session::StudyDatabase db = session::StudyDatabase::open(dir / "study.sqlite", session::OpenMode::kRunner);
  session::StudyRunner runner(db, [&o](const session::SubjectRecord& s, const HapticProfile& e) {
    return o.model ? makeSimulatedParticipant(s, e, *o.model) : makeSimulatedParticipant(s, e);
  });
  const int total = static_cast<int>(db.trials().size());
  int done = 0;
  InSilicoResult result;
  result.study = study;
  session::RunOptions run;
  HATTR_THROW_UNLESS(o.threads >= 0, "threads: expected 0 (as many as the hardware runs) or more, got {}", o.threads);
  run.subjects_at_once = o.threads > 0 ? o.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  run.progress = [&](const session::RunProgress&) {
    ++done;
    if (o.progress) o.progress("trials", done, total);
  };
  result.trials = runner.run(run);
  for (const auto& t : db.trials()) result.servo_ticks += static_cast<std::uint64_t>(t.sample_count);

  // Analyze and report.
  result.database = dir / "study.sqlite";
  report::AnalysisOptions analysis_options;
  if (o.progress) analysis_options.progress = [&o](int scored, int all) { o.progress("scoring", scored, all); };
  result.analysis = report::analyzeStudy(db, analysis_options);
  report::storeAnalysis(db, result.analysis);
  if (o.write_report) {
    if (o.progress) o.progress("report", 0, 1);
    report::writeAnalysisCsv(result.analysis, dir);
    report::writeTrialsCsv(db, result.analysis, result.analysis.options, dir / "trials.csv");
    result.report_html = report::writeStudyReport(db, result.analysis, dir);
  }
  return result;
}

}  // namespace hattr::sim
