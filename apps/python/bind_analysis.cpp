// The paper's evaluation from Python: preprocessing, DTW, the trial scorer, the balanced
// two-way ANOVA and Tukey's HSD. Long calls release the GIL, so Python threads run them in
// parallel. Statistics come back as plain records (dicts) that pandas.DataFrame takes as they are.

#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "hattr/analysis/anova.hpp"
#include "hattr/analysis/dtw.hpp"
#include "hattr/analysis/kinematics.hpp"
#include "hattr/analysis/learning_curve.hpp"
#include "hattr/analysis/lmm.hpp"
#include "hattr/analysis/preprocess.hpp"
#include "hattr/analysis/trial_score.hpp"
#include "hattr/core/error.hpp"
#include "hattr/io/table_csv.hpp"

namespace hattr::python {
namespace {

using Array = FloatArray;
constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// A 1-D float64 array's values, without copying (the array outlives the call that reads them).
std::span<const double> valuesOf(const Array& array, std::string_view name) {
  HATTR_THROW_UNLESS(array.ndim() == 1, "{}: expected a one-dimensional array; got {} dimensions", name, array.ndim());
  return {array.data(), static_cast<std::size_t>(array.size())};
}

/// Many 1-D arrays as spans over their memory (the arrays outlive the call that reads them).
std::vector<std::span<const double>> spansOf(const std::vector<Array>& arrays) {
  std::vector<std::span<const double>> spans;
  spans.reserve(arrays.size());
  for (const Array& array : arrays) spans.emplace_back(array.data(), static_cast<std::size_t>(array.size()));
  return spans;
}

/// Many 1-D arrays as the library's series. Reads the arrays' memory only: call it with the GIL
/// released, while the arrays (held by the caller's arguments) are alive.
std::vector<std::vector<double>> seriesOf(const std::vector<Array>& arrays) {
  std::vector<std::vector<double>> series;
  series.reserve(arrays.size());
  for (const Array& array : arrays) series.emplace_back(array.data(), array.data() + array.size());
  return series;
}

/// A sequence of numeric series as float64 arrays, each checked (InputError naming name[i]).
std::vector<Array> arraysOf(const py::sequence& sequence, std::string_view name) {
  HATTR_THROW_UNLESS(!py::isinstance<py::str>(sequence), "{}: expected a sequence of series, got a string", name);
  std::vector<Array> arrays;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    const std::string item = fmt::format("{}[{}]", name, i);
    arrays.push_back(floatArray(sequence[i], item));
    HATTR_THROW_UNLESS(arrays.back().ndim() == 1, "{}: expected a one-dimensional array; got {} dimensions", item,
                       arrays.back().ndim());
  }
  return arrays;
}

py::array_t<double> toArray(std::vector<double> values) { return py::array_t<double>(py::cast(std::move(values))); }

/// Level names from any iterable (a list, a pandas column of strings or numbers), as text.
std::vector<std::string> levelsOf(const py::iterable& values, std::string_view name) {
  HATTR_THROW_UNLESS(!py::isinstance<py::str>(values) && !py::isinstance<py::bytes>(values),
                     "{}: expected one level per observation (a list or a column), got a string", name);
  std::vector<std::string> out;
  for (const py::handle value : values) out.emplace_back(py::str(value));
  return out;
}

analysis::TwoWayData twoWayData(const py::iterable& a, const py::iterable& b, const py::object& y,
                                const std::string& a_name, const std::string& b_name) {
  const Array y_array = floatArray(y, "y");
  const std::span<const double> response = valuesOf(y_array, "y");
  return {.a_name = a_name, .b_name = b_name, .a = levelsOf(a, "a"), .b = levelsOf(b, "b"),
          .y = std::vector<double>(response.begin(), response.end())};
}

py::dict anovaRowRecord(const analysis::AnovaRow& r) {
  return py::dict(py::arg("source") = r.source, py::arg("df") = r.df, py::arg("sum_sq") = r.sum_sq,
                  py::arg("mean_sq") = r.mean_sq, py::arg("f") = r.f, py::arg("p") = r.p,
                  py::arg("partial_eta_sq") = r.partial_eta_sq, py::arg("error_term") = r.error_term);
}

py::dict scoreRecord(const analysis::TrialScore& s) {
  return py::dict(py::arg("x") = s.x, py::arg("y") = s.y, py::arg("z") = s.z, py::arg("fx") = s.fx,
                  py::arg("fy") = s.fy, py::arg("fz") = s.fz, py::arg("shape") = s.shape(),
                  py::arg("force") = s.force());
}

analysis::Factor factorOf(const std::string& name, const analysis::TwoWayData& data) {
  if (name == "a" || name == "A" || name == data.a_name) return analysis::Factor::kA;
  if (name == "b" || name == "B" || name == data.b_name) return analysis::Factor::kB;
  throw InputError(fmt::format("tukey_hsd: factor \"{}\": expected \"{}\" or \"{}\" (or a, b)", name, data.a_name,
                               data.b_name));
}

void bindPreprocessing(py::module_& m) {
  m.def(
      "normalize", [](const py::object& values, const std::string& how) {
        return toArray(analysis::normalize(valuesOf(floatArray(values, "values"), "values"), analysis::parseNormalization(how)));
      },
      py::arg("values"), py::arg("how") = "paper",
      "The values normalized: 'paper' ((x − mean) / (max − min), hattr's reading of the paper), 'zscore' "
      "((x − mean) / sd, R's scale()) or 'none'. Dimensionless (none: unchanged).");
  m.def(
      "time_scale", [](const py::object& trial_t_s, const py::object& expert_t_s) {
        return toArray(analysis::timeScale(valuesOf(floatArray(trial_t_s, "trial_t_s"), "trial_t_s"), valuesOf(floatArray(expert_t_s, "expert_t_s"), "expert_t_s")));
      },
      py::arg("trial_t_s"), py::arg("expert_t_s"),
      "The trial's time stamps [s] mapped linearly onto the expert's span (first to first, last to last).");
  m.def(
      "interpolate_at", [](const py::object& t_s, const py::object& values, const py::object& at_t_s) {
        return toArray(analysis::interpolateAt(valuesOf(floatArray(t_s, "t_s"), "t_s"), valuesOf(floatArray(values, "values"), "values"),
                                               valuesOf(floatArray(at_t_s, "at_t_s"), "at_t_s")));
      },
      py::arg("t_s"), py::arg("values"), py::arg("at_t_s"),
      "Linear interpolation of (t_s, values) at the times at_t_s [s], each within [t_s[0], t_s[-1]].");
  m.def(
      "preprocess_trial",
      [](const py::object& trial_t_s, const py::object& trial_values, const py::object& expert_t_s, const std::string& how) {
        return toArray(analysis::preprocessTrial(valuesOf(floatArray(trial_t_s, "trial_t_s"), "trial_t_s"), valuesOf(floatArray(trial_values, "trial_values"), "trial_values"),
                                                 valuesOf(floatArray(expert_t_s, "expert_t_s"), "expert_t_s"), analysis::parseNormalization(how)));
      },
      py::arg("trial_t_s"), py::arg("trial_values"), py::arg("expert_t_s"), py::arg("how") = "paper",
      "The paper's preprocessing of one trial channel: normalized, time-scaled onto the expert's span and "
      "interpolated at every expert time stamp; one value per expert time step.");
}

void bindDtw(py::module_& m) {
  m.def(
      "dtw",
      [](const py::object& a, const py::object& b, const std::string& cost, std::optional<double> band_fraction,
         double abandon_above) {
        const auto options = dtwOptions(cost, band_fraction, abandon_above);
        const Array a_array = floatArray(a, "a"), b_array = floatArray(b, "b");
        const std::span<const double> va = valuesOf(a_array, "a"), vb = valuesOf(b_array, "b");
        py::gil_scoped_release unlocked;
        return analysis::dtwDistance(va, vb, options);
      },
      py::arg("a"), py::arg("b"), py::kw_only(), py::arg("cost") = "abs", py::arg("band_fraction") = py::none(),
      py::arg("abandon_above") = kInfinity,
      "DTW cost of two series: cost 'abs' (|a − b|, the paper's) or 'sq'; band_fraction: Sakoe–Chiba band as a "
      "fraction of the longer series (None: no band); a result above abandon_above comes back as inf. In the "
      "series' unit (its square for 'sq'). Releases the GIL.");
  m.def(
      "dtw_with_path",
      [](const py::object& a, const py::object& b, const std::string& cost, std::optional<double> band_fraction) {
        auto options = dtwOptions(cost, band_fraction, kInfinity);
        options.want_path = true;
        const Array a_array = floatArray(a, "a"), b_array = floatArray(b, "b");
        const std::span<const double> va = valuesOf(a_array, "a"), vb = valuesOf(b_array, "b");
        analysis::DtwResult result;
        {
          py::gil_scoped_release unlocked;
          result = analysis::dtw(va, vb, options);
        }
        py::array_t<std::int64_t> path({static_cast<py::ssize_t>(result.path.size()), py::ssize_t{2}});
        auto out = path.mutable_unchecked<2>();
        for (std::size_t k = 0; k < result.path.size(); ++k) {
          out(static_cast<py::ssize_t>(k), 0) = static_cast<std::int64_t>(result.path[k].i);
          out(static_cast<py::ssize_t>(k), 1) = static_cast<std::int64_t>(result.path[k].j);
        }
        return py::make_tuple(result.cost, path);
      },
      py::arg("a"), py::arg("b"), py::kw_only(), py::arg("cost") = "abs", py::arg("band_fraction") = py::none(),
      "(cost, path): the DTW cost and its warping path, an (k, 2) int64 array of matched indices (i into a, "
      "j into b) from (0, 0) to (len(a) − 1, len(b) − 1). Releases the GIL.");
  m.def(
      "dtw_batch",
      [](const py::sequence& a_series, const py::sequence& b_series, const std::string& cost,
         std::optional<double> band_fraction, double abandon_above, unsigned threads) {
        const auto options = dtwOptions(cost, band_fraction, abandon_above);
        const std::vector<Array> a = arraysOf(a_series, "a"), b = arraysOf(b_series, "b");
        std::vector<double> costs;
        {
          py::gil_scoped_release unlocked;
          costs = analysis::dtwBatch(spansOf(a), spansOf(b), options, threads);
        }
        return toArray(std::move(costs));
      },
      py::arg("a"), py::arg("b"), py::kw_only(), py::arg("cost") = "abs", py::arg("band_fraction") = py::none(),
      py::arg("abandon_above") = kInfinity, py::arg("threads") = 1,
      "DTW costs of many pairs: result[p] = dtw(a[p], b[p]). Pairs of equal lengths share SIMD lanes; up to "
      "`threads` threads (never more than the hardware runs at once) share the pairs, with the same costs, to "
      "the bit, on any number. Contiguous float64 arrays are read in place without the GIL (others are "
      "converted first), so batches from several Python threads also run in parallel.");
  m.def(
      "dtw_cost_matrix",
      [](const py::sequence& series_list, const std::string& cost, std::optional<double> band_fraction,
         unsigned threads) {
        const auto options = dtwOptions(cost, band_fraction, kInfinity);
        const std::vector<Array> series = arraysOf(series_list, "series");
        py::gil_scoped_release unlocked;
        return analysis::dtwCostMatrix(seriesOf(series), options, threads);
      },
      py::arg("series"), py::kw_only(), py::arg("cost") = "abs", py::arg("band_fraction") = py::none(),
      py::arg("threads") = 2,
      "The symmetric matrix of DTW costs between every two series (zero diagonal), on `threads` threads.");
  m.def("dtw_simd_target", &analysis::dtwSimdTarget, "The instruction set the DTW kernels use here ('AVX2', ...).");
}

void bindScorer(py::module_& m) {
  py::class_<analysis::TrialScorer>(
      m, "TrialScorer",
      "The paper's two scores of trials against one expert profile, as the study report computes them: over "
      "each writing span, channels normalized, time-scaled onto the expert's steps, DTW per channel. shape = "
      "x + y, force = fx + fy + fz (z on its own). Normalized units.")
      .def(py::init([](const HapticProfile& expert, const std::string& normalization, const std::string& cost,
                       std::optional<double> band_fraction) {
             return analysis::TrialScorer(expert, {.normalization = analysis::parseNormalization(normalization),
                                                   .cost = analysis::parseDtwCost(cost),
                                                   .band_fraction = band_fraction.value_or(-1.0)});
           }),
           py::arg("expert"), py::kw_only(), py::arg("normalization") = "paper", py::arg("cost") = "abs",
           py::arg("band_fraction") = py::none())
      .def(
          "score",
          [](const analysis::TrialScorer& scorer, const HapticProfile& trial) {
            analysis::TrialScore s;
            {
              py::gil_scoped_release unlocked;
              s = scorer.score(trial);
            }
            return scoreRecord(s);
          },
          py::arg("trial"), "One trial's costs: {x, y, z, fx, fy, fz, shape, force}. Releases the GIL.")
      .def(
          "score_all",
          [](const analysis::TrialScorer& scorer, const py::sequence& trial_list, unsigned threads) {
            // The profiles, held here (the caller may change its list while the GIL is released).
            std::vector<py::object> held;
            std::vector<const HapticProfile*> trials;
            for (std::size_t i = 0; i < trial_list.size(); ++i) {
              held.push_back(trial_list[i]);
              HATTR_THROW_UNLESS(py::isinstance<HapticProfile>(held.back()),
                                 "score_all: trials[{}]: expected a hattr.HapticProfile, got {}", i,
                                 std::string(py::str(py::type::of(held.back()).attr("__name__"))));
              trials.push_back(held.back().cast<const HapticProfile*>());
            }
            std::vector<analysis::TrialScore> scores;
            {
              py::gil_scoped_release unlocked;
              scores = scorer.scoreAll(trials, threads);
            }
            py::list records;
            for (const analysis::TrialScore& s : scores) records.append(scoreRecord(s));
            return records;
          },
          py::arg("trials"), py::kw_only(), py::arg("threads") = 1,
          "Every trial's costs (records, one per trial), the channels shared by `threads` threads.")
      .def_property_readonly("expert_samples", &analysis::TrialScorer::expertSamples,
                             "The expert time steps each trial is resampled to.");
}

void bindStatistics(py::module_& m) {
  py::class_<analysis::AnovaTable>(m, "AnovaTable", "A two-way ANOVA table, as R's summary(aov()).")
      .def_property_readonly(
          "rows",
          [](const analysis::AnovaTable& t) {
            py::list rows;
            for (const analysis::AnovaRow& r : t.rows) rows.append(anovaRowRecord(r));
            return rows;
          },
          "Records {source, df, sum_sq, mean_sq, f, p, partial_eta_sq, error_term}: A, B, A:B (with replicates), "
          "Residuals. f, p and partial_eta_sq are nan on Residuals. pandas.DataFrame(table.rows) is the table.")
      .def("row", [](const analysis::AnovaTable& t, const std::string& source) { return anovaRowRecord(t.row(source)); },
           py::arg("source"), "The row named source ('mode', 'mode:subject', 'Residuals', ...).")
      .def_readonly("replicates", &analysis::AnovaTable::replicates, "Observations per cell.")
      .def_readonly("a_levels", &analysis::AnovaTable::a_levels)
      .def_readonly("b_levels", &analysis::AnovaTable::b_levels);

  py::class_<analysis::TukeyResult>(m, "TukeyResult", "Tukey's honest significant differences, as R's TukeyHSD().")
      .def_readonly("factor", &analysis::TukeyResult::factor)
      .def_readonly("confidence", &analysis::TukeyResult::confidence)
      .def_readonly("error_term", &analysis::TukeyResult::error_term)
      .def_readonly("error_mean_sq", &analysis::TukeyResult::error_mean_sq)
      .def_readonly("error_df", &analysis::TukeyResult::error_df)
      .def_property_readonly(
          "comparisons",
          [](const analysis::TukeyResult& t) {
            py::list rows;
            for (const analysis::TukeyComparison& c : t.comparisons) {
              rows.append(py::dict(py::arg("comparison") = c.comparison, py::arg("level") = c.level,
                                   py::arg("other_level") = c.other_level, py::arg("diff") = c.diff,
                                   py::arg("lower") = c.lower, py::arg("upper") = c.upper,
                                   py::arg("p_adjusted") = c.p_adjusted));
            }
            return rows;
          },
          "Records {comparison, level, other_level, diff, lower, upper, p_adjusted} in R's order.");

  m.def(
      "two_way_anova",
      [](const py::iterable& a, const py::iterable& b, const py::object& y, const std::string& a_name,
         const std::string& b_name, bool b_random) {
        return analysis::twoWayAnova(twoWayData(a, b, y, a_name, b_name), {.b_random = b_random});
      },
      py::arg("a"), py::arg("b"), py::arg("y"), py::kw_only(), py::arg("a_name") = "A", py::arg("b_name") = "B",
      py::arg("b_random") = false,
      "Balanced two-way ANOVA of response y (caller's unit) by factor levels a and b (any values, compared as "
      "text; levels in order of first appearance). With replicates: A + B + A:B; without: A + B. b_random: B is "
      "random and A is tested against A:B. InputError for an unbalanced design, naming the cells.");
  m.def(
      "tukey_hsd",
      [](const py::iterable& a, const py::iterable& b, const py::object& y, const std::string& factor,
         const std::string& a_name, const std::string& b_name, bool b_random, double confidence) {
        const analysis::TwoWayData data = twoWayData(a, b, y, a_name, b_name);
        return analysis::tukeyHsd(data, factorOf(factor, data), {.b_random = b_random}, confidence);
      },
      py::arg("a"), py::arg("b"), py::arg("y"), py::kw_only(), py::arg("factor") = "a", py::arg("a_name") = "A",
      py::arg("b_name") = "B", py::arg("b_random") = false, py::arg("confidence") = 0.95,
      "Tukey HSD between the levels of one factor ('a', 'b' or its name), with the error term the ANOVA uses.");
  m.def(
      "describe_groups",
      [](const py::iterable& a, const py::iterable& b, const py::object& y, const std::string& by) {
        const analysis::Grouping grouping = by == "a" ? analysis::Grouping::kA
                                            : by == "b" ? analysis::Grouping::kB
                                            : by == "cells"
                                                ? analysis::Grouping::kCells
                                                : throw InputError(fmt::format(
                                                      "describe_groups: by \"{}\": expected a, b or cells", by));
        py::list rows;
        for (const analysis::GroupStats& g : analysis::describeGroups(twoWayData(a, b, y, "A", "B"), grouping)) {
          rows.append(py::dict(py::arg("a") = g.a_level, py::arg("b") = g.b_level, py::arg("count") = g.stats.count,
                               py::arg("mean") = g.stats.mean, py::arg("variance") = g.stats.variance,
                               py::arg("sd") = g.stats.sd));
        }
        return rows;
      },
      py::arg("a"), py::arg("b"), py::arg("y"), py::kw_only(), py::arg("by") = "a",
      "Count, mean, variance and sd (n − 1) of y per level of a, of b, or per cell: records.");
}

/// A table for the mixed model: a CSV file's path, or a mapping of column names to
/// sequences (a dict, a pandas DataFrame). A column of numbers stays numbers; any other
/// column is text, each value as str() gives it.
analysis::DataTable dataTableOf(const py::object& data) {
  if (py::isinstance<py::str>(data) || py::hasattr(data, "__fspath__")) {
    const std::string path = py::str(data);
    const io::Table t = io::readTable(path);
    return analysis::dataTableFromText(t.columns, t.rows, path);
  }
  HATTR_THROW_UNLESS(py::hasattr(data, "keys"), "lmm: data: expected a CSV file's path or a mapping of column names to "
                     "sequences (a dict or a pandas DataFrame), got {}", std::string(py::str(data.get_type())));
  analysis::DataTable table;
  table.source = "data";
  for (const py::handle key : data.attr("keys")()) {
    analysis::DataColumn column{py::str(key), {}, {}};
    const py::object values = data[key];
    bool numbers = true;
    std::vector<std::string> text;
    for (const py::handle v : values) {
      // None, and NaN among text (pandas' missing values), are missing: "NA", which fitting refuses.
      const bool number = PyNumber_Check(v.ptr()) != 0 && !py::isinstance<py::str>(v) && !py::isinstance<py::bool_>(v);
      numbers = numbers && number;
      const double value = number ? v.cast<double>() : 0.0;
      if (number) column.numbers.push_back(value);
      text.push_back(v.is_none() || (number && std::isnan(value)) ? std::string("NA") : std::string(py::str(v)));
    }
    if (!numbers) {
      column.numbers.clear();
      column.text = std::move(text);
    }
    table.columns.push_back(std::move(column));
  }
  return table;
}

analysis::LmmOptions lmmOptionsOf(bool ml, const std::map<std::string, std::string>& reference,
                                  const std::vector<std::string>& factors) {
  return {.reml = !ml, .reference = reference, .factors = std::set<std::string>(factors.begin(), factors.end())};
}

void bindMixedModels(py::module_& m) {
  m.def(
      "lmm",
      [](const py::object& data, const std::string& formula, bool ml, const std::map<std::string, std::string>& reference,
         const std::vector<std::string>& factors) {
        const analysis::DataTable table = dataTableOf(data);
        const analysis::LmmOptions options = lmmOptionsOf(ml, reference, factors);
        nlohmann::json fit;
        {
          const py::gil_scoped_release release;
          fit = analysis::toJson(analysis::fitLmm(table, formula, options));
        }
        return toPython(fit);
      },
      py::arg("data"), py::arg("formula"), py::kw_only(), py::arg("ml") = false,
      py::arg("reference") = std::map<std::string, std::string>{}, py::arg("factors") = std::vector<std::string>{},
      "Linear mixed model as R's lme4::lmer with lmerTest (REML unless ml): data a CSV path or a mapping of "
      "columns (a dict, a pandas DataFrame); formula in lme4's language; reference {factor: baseline level}; "
      "factors: numeric columns to treat as factors. Levels sort as R sorts them in the C locale (bytes); "
      "missing values (None, NaN) are refused. Returns the record `hattr lmm --json` prints for the model.");
  m.def(
      "compare_lmm",
      [](const py::object& data, const std::vector<std::string>& formulas, const std::map<std::string, std::string>& reference,
         const std::vector<std::string>& factors) {
        const analysis::DataTable table = dataTableOf(data);
        const analysis::LmmOptions options = lmmOptionsOf(false, reference, factors);
        nlohmann::json tests = nlohmann::json::array();
        {
          const py::gil_scoped_release release;
          for (const auto& t : analysis::compareLmms(table, formulas, options)) tests.push_back(analysis::toJson(t));
        }
        return toPython(tests);
      },
      py::arg("data"), py::arg("formulas"), py::kw_only(), py::arg("reference") = std::map<std::string, std::string>{},
      py::arg("factors") = std::vector<std::string>{},
      "Likelihood-ratio tests between nested models, as lme4's anova(m1, m2, ...): each refitted by maximum "
      "likelihood, ordered by size, each tested against the one before. Records {smaller, larger, chi_sq, df, p}.");
}

void bindKinematicsAndCurves(py::module_& m) {
  m.def(
      "kinematics",
      [](const HapticProfile& profile, double cutoff_hz) {
        nlohmann::json k;
        {
          const py::gil_scoped_release release;
          k = analysis::toJson(analysis::trialKinematics(profile, {.cutoff_hz = cutoff_hz}));
        }
        return toPython(k);
      },
      py::arg("profile"), py::kw_only(), py::arg("cutoff_hz") = 10.0,
      "Handwriting kinematics of a profile, as `hattr kinematics --json` gives each trial: duration_s, "
      "writing_time_s, in_air_time_s, strokes, pen_lifts, path_length_m, mean_speed_m_per_s, peak_speed_m_per_s, "
      "velocity_peaks, normalized_jerk (None without a stroke of 8 samples), mean_normal_force_N, "
      "peak_normal_force_N. Positions low-passed at cutoff_hz (0: raw) before differentiating.");
  m.def(
      "fit_learning_curve",
      [](const py::object& n, const py::object& y, const std::string& law, double confidence) {
        const Array trials = floatArray(n, "n");
        const Array scores = floatArray(y, "y");
        HATTR_THROW_UNLESS(law == "exponential" || law == "power",
                           "fit_learning_curve: law \"{}\": expected exponential or power", law);
        const std::span<const double> a = valuesOf(trials, "n");
        const std::span<const double> b = valuesOf(scores, "y");
        return toPython(analysis::toJson(analysis::fitLearningCurve(
            {a.begin(), a.end()}, {b.begin(), b.end()},
            law == "power" ? analysis::CurveLaw::kPower : analysis::CurveLaw::kExponential, confidence)));
      },
      py::arg("n"), py::arg("y"), py::kw_only(), py::arg("law") = "exponential", py::arg("confidence") = 0.95,
      "Fits a law of practice to scores y at trial numbers n (from 1): exponential a + b·exp(−c(n − 1)) or power "
      "a + b·n^(−c), as R's nls(): {law, asymptote, amplitude, rate (each {estimate, std_error, lower, upper}), "
      "rss, sigma, points, confidence, note}.");
}

}  // namespace

void bindAnalysis(py::module_& m) {
  bindPreprocessing(m);
  bindDtw(m);
  bindScorer(m);
  bindStatistics(m);
  bindMixedModels(m);
  bindKinematicsAndCurves(m);
}

}  // namespace hattr::python
