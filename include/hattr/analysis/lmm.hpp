#pragma once
/// Linear mixed-effects models, fitted by REML or maximum likelihood as R's lme4::lmer()
/// fits them, with lmerTest's Satterthwaite degrees of freedom for the fixed effects and
/// its type III F tests of the terms: the analysis for data a balanced ANOVA cannot take
/// (a missing trial, a subject who missed a session, groups between subjects, covariates
/// such as the trial number). docs/analysis.md gives the model, the formula language and
/// how the tests' reference values were made with R.
///
/// The model is y = Xβ + Zb + ε with b = Λ(θ)u, u ~ N(0, σ²I), ε ~ N(0, σ²I): lme4's
/// parameterization. The profiled deviance is minimized over θ (bounded Nelder-Mead, then
/// restarted from its best point until it no longer improves); β and σ follow in closed form.
///
/// R's conventions throughout, so a fit can be compared with lme4 line by line: treatment
/// contrasts, a factor's levels sorted (byte order, as R in the C locale; a factor of
/// numbers sorted by value), the first level the baseline unless a reference is given,
/// coefficient names as "modePCONTROL:trial", terms ordered by degree, a rank-deficient
/// fixed-effects matrix reduced by dropping the later of dependent columns (named in the
/// fit's warnings), "(1 | a/b)" expanded to "(1 | b:a) + (1 | a)" and "(x || g)" to
/// independent terms named "g", "g.1", ....
///
/// Offline analysis code: any thread but the servo thread; no shared state. Bad input
/// (a formula that does not parse, an unknown column, a factor with one level, a missing or
/// non-finite value in a column the formula uses) throws hattr::InputError naming what and
/// where. A boundary (singular) fit is not an error: it is flagged and explained.

#include <cstddef>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace hattr::analysis {

/// A table to fit: named columns of text cells (as read from a CSV file) or of numbers.
/// A text column whose every cell is a number is numeric; any other is a factor.
struct DataColumn {
  std::string name;
  std::vector<std::string> text;  ///< cells as text (used unless empty)
  std::vector<double> numbers;    ///< cells as numbers (used when `text` is empty)
};

struct DataTable {
  std::vector<DataColumn> columns;
  std::string source = "data";  ///< for messages: the file name
};

/// A table of text cells (a CSV file's header and rows) as a DataTable.
[[nodiscard]] DataTable dataTableFromText(const std::vector<std::string>& header,
                                          const std::vector<std::vector<std::string>>& rows, std::string source);

struct LmmOptions {
  bool reml = true;                             ///< REML (lme4's default) or maximum likelihood
  std::map<std::string, std::string> reference;  ///< a factor's baseline level ("mode" -> "BASIC")
  std::set<std::string> factors;                 ///< numeric columns to treat as factors
  bool tests = true;  ///< Satterthwaite degrees of freedom, p-values and the term F tests
};

/// One fixed-effect coefficient, a row of lmerTest's summary().
struct LmmCoefficient {
  std::string name;        ///< R's column name: "(Intercept)", "modePCONTROL", "modePCONTROL:trial"
  double estimate = 0.0;   ///< [response unit per predictor unit]
  double std_error = 0.0;  ///< same unit
  double df = 0.0;         ///< Satterthwaite's denominator degrees of freedom
  double t = 0.0;          ///< estimate / std_error
  double p = 0.0;          ///< two-sided P(|T(df)| > |t|)
  double lower = 0.0;      ///< 95 % interval, estimate ± t(0.975, df) × std_error (lmerTest's confint)
  double upper = 0.0;
};

/// The F test of one term, a row of lmerTest's anova(type = 3).
struct LmmTermTest {
  std::string term;   ///< "mode", "mode:trial"
  double num_df = 0;  ///< the hypothesis' rank
  double den_df = 0;  ///< Satterthwaite's denominator degrees of freedom
  double f = 0.0;
  double p = 0.0;
};

/// A variance component: a standard deviation of a random effect (second name empty),
/// a correlation between two of one group's effects, or the residual (group "Residual").
struct LmmVarianceComponent {
  std::string group;   ///< "subject", "class:school", "subject.1", "Residual"
  std::string effect;  ///< "(Intercept)", "trial"; empty for the residual
  std::string other;   ///< for a correlation, the second effect; else empty
  double value = 0.0;  ///< a standard deviation [response unit] or a correlation
};

struct LmmGroup {
  std::string name;  ///< the grouping factor ("subject", "class:school")
  std::size_t levels = 0;
};

/// A fitted model.
struct LmmFit {
  std::string formula;
  std::string response;
  bool reml = true;
  std::size_t observations = 0;
  std::vector<LmmGroup> groups;
  std::vector<LmmCoefficient> fixed;
  std::vector<LmmTermTest> terms;
  std::vector<LmmVarianceComponent> variances;  ///< as R's as.data.frame(VarCorr(fit))
  std::vector<double> theta;                    ///< lme4's θ (relative covariance factors)
  double sigma = 0.0;                            ///< residual standard deviation
  double criterion = 0.0;       ///< REML criterion or deviance: -2 × the (restricted) log-likelihood
  double log_likelihood = 0.0;  ///< -criterion / 2, as R's logLik()
  double aic = 0.0;
  double bic = 0.0;
  std::size_t parameters = 0;  ///< fixed effects + θ + σ, as AIC counts them
  bool singular = false;       ///< a variance or correlation on its boundary (lme4's isSingular)
  std::vector<std::string> warnings;  ///< singular fit, dropped columns, a doubtful Hessian
  std::size_t evaluations = 0;        ///< deviance evaluations the optimizer took
  std::vector<std::string> data_columns;  ///< the columns the formula uses
};

/// Fits `formula` ("y ~ mode * trial + (1 + trial | subject)") to `data`. Throws
/// InputError as described above; the model needs at least one random-effect term, and
/// each grouping factor fewer levels than observations.
[[nodiscard]] LmmFit fitLmm(const DataTable& data, std::string_view formula, const LmmOptions& options = {});

/// A likelihood-ratio test between two nested models, as lme4's anova(smaller, larger).
struct LikelihoodRatioTest {
  std::string smaller;
  std::string larger;
  double chi_sq = 0.0;
  std::size_t df = 0;
  double p = 0.0;
};

/// The test of `smaller` against `larger`: both maximum-likelihood fits (lme4 refits REML
/// fits by ML for this; fit with reml = false) of the same observations, `larger` with more
/// parameters. Throws InputError otherwise.
[[nodiscard]] LikelihoodRatioTest likelihoodRatio(const LmmFit& smaller, const LmmFit& larger);

/// Fits each formula and tests each against the next larger, as lme4's anova(m1, m2, ...):
/// every model refitted by maximum likelihood, ordered by number of parameters, each tested
/// against the one before. Throws InputError for fewer than two formulas or two of equal size.
[[nodiscard]] std::vector<LikelihoodRatioTest> compareLmms(const DataTable& data, const std::vector<std::string>& formulas,
                                                           const LmmOptions& options = {});

/// The fit as JSON (`hattr lmm --json`, Python): every field above; non-finite numbers null.
[[nodiscard]] nlohmann::json toJson(const LmmFit& fit);
[[nodiscard]] nlohmann::json toJson(const LikelihoodRatioTest& test);

}  // namespace hattr::analysis
