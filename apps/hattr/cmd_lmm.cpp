// hattr lmm: a linear mixed model of a CSV table, as R's lme4 + lmerTest fit it.

#include <cmath>
#include <iostream>
#include <map>
#include <set>

#include <fmt/format.h>

#include "cli_common.hpp"
#include "hattr/analysis/lmm.hpp"
#include "hattr/core/error.hpp"
#include "hattr/io/table_csv.hpp"

namespace hattr::cli {
namespace {

struct LmmCommandOptions {
  std::string file;
  std::vector<std::string> formulas;
  std::vector<std::string> references;
  std::vector<std::string> factors;
  bool ml = false;
  bool json = false;
};

/// "--reference mode=BASIC" as a map.
std::map<std::string, std::string> parseReferences(const std::vector<std::string>& items) {
  std::map<std::string, std::string> out;
  for (const std::string& item : items) {
    const auto equals = item.find('=');
    HATTR_THROW_UNLESS(equals != std::string::npos && equals > 0 && equals + 1 < item.size(),
                       "--reference '{}': expected COLUMN=LEVEL, e.g. mode=BASIC", item);
    out[item.substr(0, equals)] = item.substr(equals + 1);
  }
  return out;
}

std::string cell(double v, const char* format = "{:.6g}") {
  return std::isfinite(v) ? fmt::format(fmt::runtime(format), v) : "NA";
}

std::string pValue(double p) {
  if (!std::isfinite(p)) return "NA";
  return p < 2e-16 ? "< 2e-16" : fmt::format("{:.4g}", p);
}

/// The fit in the layout of R's summary() of an lmerTest fit.
void printFit(const analysis::LmmFit& fit, const std::string& file) {
  std::cout << fmt::format("Linear mixed model fit by {} (t tests use Satterthwaite's method)\nFormula: {}\nData: {} "
                           "({} observations",
                           fit.reml ? "REML" : "maximum likelihood", fit.formula, file, fit.observations);
  for (const auto& g : fit.groups) std::cout << fmt::format("; {}: {} levels", g.name, g.levels);
  std::cout << fmt::format(")\n\n{} {:.6g}   AIC {:.6g}   BIC {:.6g}   log-likelihood {:.6g}\n\nRandom effects:\n",
                           fit.reml ? "REML criterion" : "deviance", fit.criterion, fit.aic, fit.bic, fit.log_likelihood);
  // One row an effect, its group named once, its correlations with the group's earlier effects.
  std::cout << fmt::format(" {:<14} {:<16} {:>10}  {}\n", "Group", "Effect", "Std.Dev.", "Corr");
  std::string last_group;
  for (const auto& v : fit.variances) {
    if (!v.other.empty()) continue;
    std::string correlations;
    for (const auto& c : fit.variances) {
      if (!c.other.empty() && c.group == v.group && c.other == v.effect) correlations += fmt::format("{:>7.3f}", c.value);
    }
    std::cout << fmt::format(" {:<14} {:<16} {:>10.5g}  {}\n", v.group == last_group ? "" : v.group, v.effect, v.value,
                             correlations);
    last_group = v.group;
  }
  std::cout << fmt::format("\nFixed effects:\n {:<24} {:>11} {:>11} {:>9} {:>9} {:>10}\n", "", "Estimate", "Std. Error",
                           "df", "t value", "Pr(>|t|)");
  for (const auto& c : fit.fixed) {
    std::cout << fmt::format(" {:<24} {:>11} {:>11} {:>9} {:>9} {:>10}\n", c.name, cell(c.estimate), cell(c.std_error),
                             cell(c.df, "{:.2f}"), cell(c.t, "{:.3f}"), pValue(c.p));
  }
  if (!fit.terms.empty()) {
    std::cout << fmt::format("\nType III tests of the terms (Satterthwaite):\n {:<24} {:>6} {:>9} {:>9} {:>10}\n", "",
                             "NumDF", "DenDF", "F value", "Pr(>F)");
    for (const auto& t : fit.terms) {
      std::cout << fmt::format(" {:<24} {:>6} {:>9} {:>9} {:>10}\n", t.term, cell(t.num_df), cell(t.den_df, "{:.2f}"),
                               cell(t.f, "{:.4g}"), pValue(t.p));
    }
  }
  for (const auto& w : fit.warnings) std::cout << "\nwarning: " << w << '\n';
}

void runLmm(const LmmCommandOptions& opt) {
  const io::Table table = io::readTable(opt.file);
  const analysis::DataTable data = analysis::dataTableFromText(table.columns, table.rows, opt.file);
  analysis::LmmOptions options;
  options.reml = !opt.ml;
  options.reference = parseReferences(opt.references);
  options.factors = std::set<std::string>(opt.factors.begin(), opt.factors.end());

  std::vector<analysis::LmmFit> fits;
  for (const std::string& f : opt.formulas) fits.push_back(analysis::fitLmm(data, f, options));
  std::vector<analysis::LikelihoodRatioTest> comparisons;
  if (opt.formulas.size() > 1) comparisons = analysis::compareLmms(data, opt.formulas, options);

  if (opt.json) {
    nlohmann::json models = nlohmann::json::array();
    for (const auto& f : fits) models.push_back(analysis::toJson(f));
    nlohmann::json tests = nlohmann::json::array();
    for (const auto& t : comparisons) tests.push_back(analysis::toJson(t));
    nlohmann::json out = {{"file", opt.file}, {"models", models}};
    if (!comparisons.empty()) out["likelihood_ratio_tests"] = tests;
    return printJson(out);
  }
  for (std::size_t i = 0; i < fits.size(); ++i) {
    if (i > 0) std::cout << "\n" << std::string(72, '-') << "\n\n";
    printFit(fits[i], opt.file);
  }
  if (comparisons.empty()) return;
  std::cout << "\nLikelihood-ratio tests (models refitted by maximum likelihood, as lme4's anova()):\n";
  for (const auto& t : comparisons) {
    std::cout << fmt::format(" {}\n   vs {}\n   Chisq {:.5g}, Df {}, Pr(>Chisq) {}\n", t.smaller, t.larger, t.chi_sq, t.df,
                             pValue(t.p));
  }
}

}  // namespace

void registerLmmCommand(CLI::App& app) {
  auto opt = std::make_shared<LmmCommandOptions>();
  auto* lmm = app.add_subcommand("lmm", "Linear mixed model of a CSV table (as R's lme4::lmer with lmerTest)");
  lmm->add_option("DATA", opt->file, "CSV table with a header row: one observation a row")->required();
  lmm->add_option("--formula", opt->formulas,
                  "lme4 formula, e.g. \"cost ~ mode * trial + (1 + trial | subject)\"; give two or more to compare "
                  "nested models by likelihood-ratio tests")
      ->required();
  lmm->add_flag("--ml", opt->ml, "Fit by maximum likelihood instead of REML");
  lmm->add_option("--reference", opt->references, "A factor's baseline level, COLUMN=LEVEL (default: the first in "
                                                 "sorted order, as R in the C locale: bytes, so B before a)");
  lmm->add_option("--factor", opt->factors, "Treat this numeric column as a factor (as R's factor())");
  lmm->add_flag("--json", opt->json, "Print JSON: models [{fixed_effects, terms, random_effects, aic, bic, ...}], "
                                     "likelihood_ratio_tests");
  lmm->callback([opt] { runLmm(*opt); });
}

}  // namespace hattr::cli
