// hattr dtw | anova | kinematics: the paper's evaluation, and handwriting kinematics, on files.

#include <iostream>
#include <sstream>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/analysis/anova.hpp"
#include "hattr/analysis/dtw.hpp"
#include "hattr/analysis/kinematics.hpp"
#include "hattr/analysis/trial_score.hpp"
#include "hattr/analysis/preprocess.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/text_file.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/io/table_csv.hpp"

namespace hattr::cli {
namespace {

struct DtwCommandOptions {
  std::string a;
  std::string b;
  std::string channels = "x,y,z,fx,fy,fz";
  double band = -1.0;
  std::string cost = "abs";
  std::string preprocess = "paper";
  bool path = false;
  bool score = false;
  bool json = false;
};

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

/// --score: the paper's two scores through the one scorer the report and the studio use.
void runScore(const DtwCommandOptions& opt, const HapticProfile& expert, const HapticProfile& trial) {
  const analysis::TrialScorer scorer(expert, {.normalization = analysis::parseNormalization(opt.preprocess),
                                              .cost = analysis::parseDtwCost(opt.cost),
                                              .band_fraction = opt.band});
  const analysis::TrialScore s = scorer.score(trial);
  const analysis::TimeSpan span = analysis::writingSpan(trial);
  const nlohmann::json json = {
      {"a", opt.a}, {"b", opt.b}, {"cost_fn", opt.cost}, {"preprocess", opt.preprocess},
      {"band", opt.band < 0.0 || opt.band >= 1.0 ? nlohmann::json(nullptr) : nlohmann::json(opt.band)},
      {"samples", scorer.expertSamples()}, {"trial_span_s", {span.begin_s, span.end_s}},
      {"cost", {{"x", s.x}, {"y", s.y}, {"z", s.z}, {"fx", s.fx}, {"fy", s.fy}, {"fz", s.fz}}},
      {"shape", s.shape()}, {"height", s.z}, {"force", s.force()}};
  if (opt.json) return printJson(json);
  std::cout << fmt::format("shape  {:.6g}  (x {:.6g}, y {:.6g})\nheight {:.6g}  (z, not part of the shape)\n"
                           "force  {:.6g}  (fx {:.6g}, fy {:.6g}, fz {:.6g})\n",
                           s.shape(), s.x, s.y, s.z, s.force(), s.fx, s.fy, s.fz);
}

void runDtw(const DtwCommandOptions& opt) {
  const HapticProfile a = io::readProfileCsv(opt.a);
  const HapticProfile b = io::readProfileCsv(opt.b);
  if (opt.score) {
    HATTR_THROW_UNLESS(!opt.path, "--path: not with --score (the scores have no single path)");
    return runScore(opt, a, b);
  }
  const std::vector<std::string> channels = splitList(opt.channels);
  HATTR_THROW_UNLESS(!channels.empty(), "--channels: expected a comma-separated list such as x,y,z,fx,fy,fz, got \"{}\"",
                     opt.channels);
  analysis::DtwOptions dtw{.cost = analysis::parseDtwCost(opt.cost),
                           .band_fraction = opt.band, .want_path = opt.path};
  const auto normalization = analysis::parseNormalization(opt.preprocess);

  // The paper's preprocessing: B onto A's time steps, each normalized; then DTW per channel.
  const std::vector<double> a_t = a.channel(Channel::kTime);
  const std::vector<double> b_t = b.channel(Channel::kTime);
  nlohmann::json costs = nlohmann::json::object();
  nlohmann::json paths = nlohmann::json::object();
  for (const std::string& name : channels) {
    const std::vector<double> a_values = analysis::normalize(a.channel(name), normalization);
    const std::vector<double> b_values = analysis::preprocessTrial(b_t, b.channel(name), a_t, normalization);
    const analysis::DtwResult r = analysis::dtw(a_values, b_values, dtw);
    costs[name] = r.cost;
    if (opt.path) {
      nlohmann::json steps = nlohmann::json::array();
      for (const auto& s : r.path) steps.push_back({s.i, s.j});
      paths[name] = steps;
    }
  }
  nlohmann::json json = {{"a", opt.a}, {"b", opt.b}, {"cost", costs}, {"cost_fn", opt.cost},
                         {"band", opt.band < 0.0 || opt.band >= 1.0 ? nlohmann::json(nullptr) : nlohmann::json(opt.band)},
                         {"preprocess", opt.preprocess}, {"samples", a.size()}};
  if (opt.path) json["path"] = paths;
  if (opt.json) return printJson(json);
  std::cout << fmt::format("DTW ({} cost, {} preprocessing, B on A's {} time steps)\n", opt.cost, opt.preprocess, a.size());
  for (const std::string& name : channels) std::cout << fmt::format("  {:<9} {:.6g}\n", name, costs[name].get<double>());
}

struct AnovaCommandOptions {
  std::string file;
  std::string response;
  std::vector<std::string> factors;
  std::string random;
  std::string tukey;
  bool json = false;
};

void runAnova(const AnovaCommandOptions& opt) {
  HATTR_THROW_UNLESS(opt.factors.size() == 2, "--factor: expected exactly two factors (--factor A --factor B), got {}",
                     opt.factors.size());
  HATTR_THROW_UNLESS(opt.random.empty() || opt.random == opt.factors[1],
                     "--random {}: expected the second factor ({}) — the first is the fixed one it tests", opt.random,
                     opt.factors[1]);
  const io::Table table = io::readTable(opt.file);
  const analysis::TwoWayData data{opt.factors[0], opt.factors[1], table.text(opt.factors[0]), table.text(opt.factors[1]),
                                  table.numbers(opt.response)};
  const analysis::AnovaOptions options{.b_random = !opt.random.empty()};
  const analysis::AnovaTable anova = analysis::twoWayAnova(data, options);
  nlohmann::json rows = nlohmann::json::array();
  for (const auto& r : anova.rows) {
    rows.push_back({{"source", r.source}, {"df", r.df}, {"ss", r.sum_sq}, {"ms", r.mean_sq}, {"f", jsonNumber(r.f)},
                    {"p", jsonNumber(r.p)}, {"partial_eta_sq", jsonNumber(r.partial_eta_sq)}, {"error_term", r.error_term}});
  }
  nlohmann::json json = {{"file", opt.file}, {"response", opt.response}, {"replicates", anova.replicates}, {"rows", rows},
                         {"random", opt.random.empty() ? nlohmann::json(nullptr) : nlohmann::json(opt.random)}};
  std::optional<analysis::TukeyResult> tukey;
  if (!opt.tukey.empty()) {
    HATTR_THROW_UNLESS(opt.tukey == opt.factors[0] || opt.tukey == opt.factors[1],
                       "--tukey {}: expected one of the factors ({}, {})", opt.tukey, opt.factors[0], opt.factors[1]);
    tukey = analysis::tukeyHsd(data, opt.tukey == opt.factors[0] ? analysis::Factor::kA : analysis::Factor::kB, options);
    nlohmann::json comparisons = nlohmann::json::array();
    for (const auto& c : tukey->comparisons) {
      comparisons.push_back({{"comparison", c.comparison}, {"diff", c.diff}, {"lwr", c.lower}, {"upr", c.upper},
                             {"p_adj", c.p_adjusted}});
    }
    json["tukey"] = {{"factor", opt.tukey}, {"error_term", tukey->error_term}, {"comparisons", comparisons}};
  }
  if (opt.json) return printJson(json);
  std::cout << fmt::format("{:<22} {:>4} {:>12} {:>12} {:>9} {:>10}\n", "", "Df", "Sum Sq", "Mean Sq", "F value", "Pr(>F)");
  for (const auto& r : anova.rows) {
    std::cout << fmt::format("{:<22} {:>4} {:>12.5g} {:>12.5g} {:>9} {:>10}\n", r.source, r.df, r.sum_sq, r.mean_sq,
                             std::isfinite(r.f) ? fmt::format("{:.4g}", r.f) : "",
                             std::isfinite(r.p) ? fmt::format("{:.4g}", r.p) : "");
  }
  if (tukey) {
    std::cout << fmt::format("\nTukey HSD on {} (95 %, error {}):\n", tukey->factor, tukey->error_term);
    for (const auto& c : tukey->comparisons) {
      std::cout << fmt::format("  {:<24} diff {:>10.4g}  [{:.4g}, {:.4g}]  p adj {:.4g}\n", c.comparison, c.diff, c.lower,
                               c.upper, c.p_adjusted);
    }
  }
}

struct KinematicsCommandOptions {
  std::vector<std::string> files;
  double cutoff_hz = 10.0;
  bool json = false;
};

/// Each profile's handwriting kinematics: SI units in JSON, millimetres in the text.
void runKinematics(const KinematicsCommandOptions& opt) {
  nlohmann::json trials = nlohmann::json::array();
  for (const std::string& file : opt.files) {
    const analysis::TrialKinematics k =
        analysis::trialKinematics(io::readProfileCsv(file), {.cutoff_hz = opt.cutoff_hz});
    nlohmann::json row = analysis::toJson(k);
    row["file"] = file;
    trials.push_back(row);
    if (opt.json) continue;
    std::cout << fmt::format(
        "{}\n  time        {:.3f} s ({:.3f} s writing, {:.3f} s in the air between strokes)\n"
        "  strokes     {} ({} pen lifts)\n  path        {:.2f} mm\n  speed       mean {:.2f} mm/s, peak {:.2f} mm/s\n"
        "  fluency     {} velocity peaks, normalized jerk {}\n  press       mean {:.3f} N, peak {:.3f} N\n",
        file, k.duration_s, k.writing_time_s, k.in_air_time_s, k.strokes, k.pen_lifts, k.path_length_m * 1e3,
        k.mean_speed_m_per_s * 1e3, k.peak_speed_m_per_s * 1e3, k.velocity_peaks,
        std::isfinite(k.normalized_jerk) ? fmt::format("{:.4g}", k.normalized_jerk) : "n/a (no stroke of 8 samples)",
        k.mean_normal_force_N, k.peak_normal_force_N);
  }
  if (opt.json) printJson({{"cutoff_hz", opt.cutoff_hz}, {"trials", trials}});
}

}  // namespace

void registerAnalysisCommands(CLI::App& app) {
  auto dtw_opt = std::make_shared<DtwCommandOptions>();
  auto* dtw = app.add_subcommand("dtw", "Per-channel DTW cost between two profiles (the paper's shape metric)");
  dtw->add_option("A", dtw_opt->a, "Reference profile (the expert's)")->required();
  dtw->add_option("B", dtw_opt->b, "Profile compared with it (a trial)")->required();
  dtw->add_option("--channels", dtw_opt->channels, "Channels, comma-separated")->capture_default_str();
  dtw->add_option("--band", dtw_opt->band, "Sakoe–Chiba band as a fraction of the length (default: none)")
      ->check(CLI::Range(0.0, 1.0));
  dtw->add_option("--cost", dtw_opt->cost, "Local cost: abs (the paper's) or sq")
      ->check(CLI::IsMember({"abs", "sq"}))
      ->capture_default_str();
  dtw->add_option("--preprocess", dtw_opt->preprocess,
                  "Normalization before DTW (B is also time-scaled onto A's steps): paper, zscore, none")
      ->check(CLI::IsMember({"paper", "zscore", "none"}))
      ->capture_default_str();
  dtw->add_flag("--path", dtw_opt->path, "Also return each channel's warping path");
  dtw->add_flag("--score", dtw_opt->score,
                "The paper's scores as the study report computes them: shape (x + y), height (z, on its own) and "
                "force (fx + fy + fz), over each profile's writing span");
  dtw->add_flag("--json", dtw_opt->json, "Print JSON: cost {channel: value}, cost_fn, band, and path when asked");
  dtw->callback([dtw_opt] { runDtw(*dtw_opt); });

  auto anova_opt = std::make_shared<AnovaCommandOptions>();
  auto* anova = app.add_subcommand("anova", "Balanced two-way ANOVA of a CSV table (like R's summary(aov(...)))");
  anova->add_option("DATA", anova_opt->file, "CSV table with a header row")->required();
  anova->add_option("--response", anova_opt->response, "Response column")->required();
  anova->add_option("--factor", anova_opt->factors, "Factor column; give two: --factor A --factor B")->required();
  anova->add_option("--random", anova_opt->random, "Treat the second factor as random (the first is tested against A:B)");
  anova->add_option("--tukey", anova_opt->tukey, "Also Tukey HSD between the levels of this factor");
  anova->add_flag("--json", anova_opt->json, "Print JSON: rows [{source, df, ss, ms, f, p, partial_eta_sq}], tukey");
  anova->callback([anova_opt] { runAnova(*anova_opt); });

  auto kin_opt = std::make_shared<KinematicsCommandOptions>();
  auto* kin = app.add_subcommand("kinematics", "Handwriting kinematics of profiles: time, pen lifts, path, speed, "
                                               "velocity peaks, normalized jerk, press (docs/analysis.md)");
  kin->add_option("PROFILE", kin_opt->files, "Profile CSV files (a trial, an expert, an imported recording)")->required();
  kin->add_option("--cutoff", kin_opt->cutoff_hz, "Low-pass cut-off for the positions [Hz]; 0: the raw samples")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  kin->add_flag("--json", kin_opt->json, "Print JSON: trials [{file, duration_s, writing_time_s, ...}], SI units");
  kin->callback([kin_opt] { runKinematics(*kin_opt); });
}

}  // namespace hattr::cli
