// The design matrices of a linear mixed model from a table and its parsed formula, with R's
// conventions: columns read as numbers or factors, levels sorted, treatment contrasts, terms
// coded as R codes them, rank-deficient columns dropped (lmm_model.hpp, docs/analysis.md).

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <numeric>
#include <unordered_map>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "lmm_model.hpp"

namespace hattr::analysis::lmm {
namespace {

// ---- Variables ----------------------------------------------------------------------

/// Parses a whole cell as a number (R's as.numeric: leading and trailing blanks allowed).
bool parseNumber(const std::string& cell, double& out) {
  const char* begin = cell.c_str();
  char* end = nullptr;
  out = std::strtod(begin, &end);
  if (end == begin) return false;
  while (*end != '\0' && std::isspace(static_cast<unsigned char>(*end)) != 0) ++end;
  return *end == '\0';
}

bool isMissing(const std::string& cell) {
  const auto first = cell.find_first_not_of(" \t");
  return first == std::string::npos || cell.substr(first) == "NA";
}

const DataColumn& findColumn(const DataTable& data, const std::string& name) {
  for (const DataColumn& c : data.columns) {
    if (c.name == name) return c;
  }
  std::string names;
  for (const DataColumn& c : data.columns) names += (names.empty() ? "" : ", ") + c.name;
  throw InputError(fmt::format("{}: the formula names column '{}', which is not in the table; columns: {}", data.source,
                               name, names));
}

std::size_t rowCount(const DataColumn& c) { return c.text.empty() ? c.numbers.size() : c.text.size(); }

/// A number as R's as.character() writes it: the fewest significant digits (up to 15) that
/// give the number back, in fixed notation unless scientific is shorter ("2.5", "1e+05").
std::string rText(double x) {
  const double rounded = std::strtod(fmt::format("{:.15g}", x).c_str(), nullptr);
  const double target = rounded == x || std::abs(rounded - x) <= 1e-15 * std::abs(x) ? rounded : x;
  int digits = 1;
  while (digits < 17 && std::strtod(fmt::format("{:.{}e}", target, digits - 1).c_str(), nullptr) != target) ++digits;
  std::string sci = fmt::format("{:.{}e}", target, digits - 1);  // "2.5e+00"; R: "2.5e+00" as "2.5e+00"
  const int exponent = target == 0.0 ? 0 : static_cast<int>(std::floor(std::log10(std::abs(target))));
  const std::string fixed = fmt::format("{:.{}f}", target, std::max(0, digits - 1 - exponent));
  return fixed.size() <= sci.size() ? fixed : sci;
}

/// Sets a factor's levels, each row's code, and the baseline first: text levels sorted by
/// bytes (R in the C locale), numbers by value and written as R writes them.
void setLevels(Variable& v, std::vector<std::string> cells, const std::vector<double>& numbers,
               const std::string& reference, const std::string& source) {
  std::vector<std::string> levels;
  if (!numbers.empty()) {
    std::vector<double> values = numbers;
    std::sort(values.begin(), values.end());
    values.erase(std::unique(values.begin(), values.end()), values.end());
    for (double x : values) levels.push_back(rText(x));
    cells.clear();
    for (double x : numbers) cells.push_back(rText(x));
  } else {
    levels = cells;
    std::sort(levels.begin(), levels.end());
    levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  }
  if (!reference.empty()) {
    const auto it = std::find(levels.begin(), levels.end(), reference);
    std::string known;
    for (const std::string& l : levels) known += (known.empty() ? "" : ", ") + l;
    HATTR_THROW_UNLESS(it != levels.end(), "{}: reference level '{}' of '{}' is not in the data; levels: {}", source,
                       reference, v.name, known);
    std::rotate(levels.begin(), it, it + 1);
  }
  std::unordered_map<std::string, int> code;
  for (std::size_t i = 0; i < levels.size(); ++i) code[levels[i]] = static_cast<int>(i);
  v.factor = true;
  v.values.clear();
  v.levels = levels;
  v.codes.resize(cells.size());
  for (std::size_t r = 0; r < cells.size(); ++r) v.codes[r] = code[cells[r]];
}

/// Reads one column the formula uses, as numbers or as a factor: a text column is numbers
/// when every cell is one (a non-finite one is refused), else a factor.
Variable readVariable(const DataTable& data, const std::string& name, bool force_factor, const LmmOptions& options) {
  const DataColumn& column = findColumn(data, name);
  Variable v;
  v.name = name;
  const auto reference = options.reference.find(name);
  const std::string ref = reference == options.reference.end() ? "" : reference->second;
  bool numeric = column.text.empty();
  if (numeric) {
    v.values = column.numbers;
  } else {
    v.values.resize(column.text.size());
    numeric = true;
    for (std::size_t r = 0; r < column.text.size(); ++r) {
      const std::string& cell = column.text[r];
      HATTR_THROW_UNLESS(!isMissing(cell), "{}: row {} of column '{}' is missing ('{}'); expected a value (remove the "
                         "row to leave it out, as R's na.omit would)", data.source, r + 1, name, cell);
      numeric = numeric && parseNumber(cell, v.values[r]);
    }
  }
  if (!numeric) {
    setLevels(v, column.text, {}, ref, data.source);
    return v;
  }
  for (std::size_t r = 0; r < v.values.size(); ++r) {
    HATTR_THROW_UNLESS(std::isfinite(v.values[r]), "{}: row {} of column '{}' is {}; expected a finite number (remove "
                       "the row to leave it out)", data.source, r + 1, name,
                       column.text.empty() ? fmt::format("{}", v.values[r]) : "'" + column.text[r] + "'");
  }
  if (force_factor) {
    setLevels(v, {}, std::vector<double>(v.values), ref, data.source);
    return v;
  }
  HATTR_THROW_UNLESS(ref.empty(), "{}: --reference names column '{}', which is numeric; a reference level needs a factor "
                     "(declare it one with --factor {})", data.source, name, name);
  return v;
}

// ---- Design matrices ----------------------------------------------------------------

/// The columns one variable contributes to a term.
struct Part {
  std::vector<std::string> names;
  std::vector<Eigen::VectorXd> columns;
};

Part partOf(const Variable& v, bool contrasts, std::size_t rows) {
  Part p;
  if (!v.factor) {
    p.names.push_back(v.name);
    p.columns.push_back(Eigen::Map<const Eigen::VectorXd>(v.values.data(), static_cast<Eigen::Index>(rows)));
    return p;
  }
  for (std::size_t level = contrasts ? 1 : 0; level < v.levels.size(); ++level) {
    Eigen::VectorXd c(static_cast<Eigen::Index>(rows));
    for (std::size_t r = 0; r < rows; ++r) c[static_cast<Eigen::Index>(r)] = v.codes[r] == static_cast<int>(level) ? 1.0 : 0.0;
    p.names.push_back(v.name + v.levels[level]);
    p.columns.push_back(std::move(c));
  }
  return p;
}

/// Drops the later of linearly dependent columns, as R's qr() with its tolerance 1e-7 and
/// lme4 do; returns the names of the columns dropped.
std::vector<std::string> dropDependentColumns(Design& d) {
  std::vector<Eigen::VectorXd> basis;
  std::vector<Eigen::Index> kept;
  std::vector<std::string> dropped;
  for (Eigen::Index c = 0; c < d.matrix.cols(); ++c) {
    Eigen::VectorXd v = d.matrix.col(c);
    const double norm = v.norm();
    for (const Eigen::VectorXd& b : basis) v -= b.dot(v) * b;  // modified Gram-Schmidt
    if (norm > 0.0 && v.norm() > 1e-7 * norm) {
      basis.push_back(v / v.norm());
      kept.push_back(c);
    } else {
      dropped.push_back(d.names[static_cast<std::size_t>(c)]);
    }
  }
  if (dropped.empty()) return dropped;
  Design reduced;
  reduced.matrix.resize(d.matrix.rows(), static_cast<Eigen::Index>(kept.size()));
  for (std::size_t k = 0; k < kept.size(); ++k) {
    reduced.matrix.col(static_cast<Eigen::Index>(k)) = d.matrix.col(kept[k]);
    reduced.names.push_back(d.names[static_cast<std::size_t>(kept[k])]);
    reduced.term_of_column.push_back(d.term_of_column[static_cast<std::size_t>(kept[k])]);
  }
  d = std::move(reduced);
  return dropped;
}

}  // namespace

std::vector<std::vector<int>> termCodes(const std::vector<Term>& terms) {
  std::vector<std::vector<int>> codes;
  for (std::size_t t = 0; t < terms.size(); ++t) {
    std::vector<int> code;
    for (int v : terms[t]) {
      Term margin = terms[t];
      margin.erase(std::find(margin.begin(), margin.end(), v));
      bool contained = margin.empty();
      for (std::size_t earlier = 0; earlier < t && !contained; ++earlier) {
        contained = std::includes(terms[earlier].begin(), terms[earlier].end(), margin.begin(), margin.end());
      }
      code.push_back(contained ? 1 : 2);
    }
    codes.push_back(code);
  }
  return codes;
}

Design designMatrix(const std::vector<Variable>& variables, bool intercept, const std::vector<Term>& terms,
                    bool full_indicators) {
  // R's coding: contrasts (1) or indicators (2) per variable of each term; without an
  // intercept, the first factor of the first term that has one is coded by indicators.
  std::vector<std::vector<int>> codes = termCodes(terms);
  for (std::size_t t = 0; t < terms.size() && !intercept; ++t) {
    const auto factor = std::find_if(terms[t].begin(), terms[t].end(),
                                     [&](int v) { return variables[static_cast<std::size_t>(v)].factor; });
    if (factor == terms[t].end()) continue;
    codes[t][static_cast<std::size_t>(factor - terms[t].begin())] = 2;
    break;
  }
  const std::size_t rows = variables.empty() ? 0 : std::max(variables[0].values.size(), variables[0].codes.size());
  std::vector<Eigen::VectorXd> columns;
  Design d;
  if (intercept) {
    columns.push_back(Eigen::VectorXd::Ones(static_cast<Eigen::Index>(rows)));
    d.names.emplace_back("(Intercept)");
    d.term_of_column.push_back(-1);
  }
  for (std::size_t t = 0; t < terms.size(); ++t) {
    // The term's columns: products of its variables' parts, the first varying fastest.
    std::vector<std::string> names{""};
    std::vector<Eigen::VectorXd> product{Eigen::VectorXd::Ones(static_cast<Eigen::Index>(rows))};
    for (std::size_t k = 0; k < terms[t].size(); ++k) {
      const Variable& v = variables[static_cast<std::size_t>(terms[t][k])];
      const bool contrasts = !full_indicators && codes[t][k] == 1;
      const Part part = partOf(v, contrasts, rows);
      std::vector<std::string> next_names;
      std::vector<Eigen::VectorXd> next;
      for (std::size_t j = 0; j < part.columns.size(); ++j) {
        for (std::size_t i = 0; i < product.size(); ++i) {
          next_names.push_back(names[i].empty() ? part.names[j] : names[i] + ":" + part.names[j]);
          next.push_back(product[i].cwiseProduct(part.columns[j]));
        }
      }
      names = std::move(next_names);
      product = std::move(next);
    }
    for (std::size_t i = 0; i < product.size(); ++i) {
      columns.push_back(std::move(product[i]));
      d.names.push_back(names[i]);
      d.term_of_column.push_back(static_cast<int>(t));
    }
  }
  d.matrix.resize(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t c = 0; c < columns.size(); ++c) d.matrix.col(static_cast<Eigen::Index>(c)) = columns[c];
  return d;
}

namespace {

/// The response and the formula's variables into `m` (all of one length); returns each
/// grouping column read as a factor (lme4's factor()), empty where a variable does not group.
std::vector<Variable> readModelVariables(const DataTable& data, const ParsedFormula& formula, const LmmOptions& options,
                                         Model& m) {
  const Variable response = readVariable(data, formula.response, false, options);
  HATTR_THROW_UNLESS(!response.factor, "{}: the response '{}' is not numeric; expected numbers", data.source, formula.response);
  const std::size_t rows = response.values.size();
  std::vector<bool> grouping(formula.variables.size(), false);
  for (const RandomTerm& r : formula.random) {
    for (int g : r.group) grouping[static_cast<std::size_t>(g)] = true;
  }
  // A column that groups is a factor there (lme4's factor()), and stays as it is elsewhere.
  std::vector<Variable> groups(formula.variables.size());
  for (std::size_t i = 0; i < formula.variables.size(); ++i) {
    const std::string& name = formula.variables[i];
    m.variables.push_back(readVariable(data, name, options.factors.count(name) > 0, options));
    if (grouping[i]) groups[i] = m.variables.back().factor ? m.variables.back() : readVariable(data, name, true, options);
    HATTR_THROW_UNLESS(rowCount(findColumn(data, name)) == rows, "{}: column '{}' has {} rows, the response {}",
                       data.source, name, rowCount(findColumn(data, name)), rows);
  }
  for (const auto& [name, level] : options.reference) {
    HATTR_THROW_UNLESS(std::find(formula.variables.begin(), formula.variables.end(), name) != formula.variables.end(),
                       "--reference {}={}: the formula '{}' has no column '{}'", name, level, formula.text, name);
  }
  HATTR_THROW_UNLESS(rows >= 2, "{}: {} rows; a mixed model needs more", data.source, rows);
  m.y = Eigen::Map<const Eigen::VectorXd>(response.values.data(), static_cast<Eigen::Index>(rows));
  return groups;
}

/// Factors in the effects, fixed or random, need two levels (R's contrasts do).
void requireTwoLevels(const DataTable& data, const Model& m, const std::vector<Term>& terms, const char* part) {
  for (const Term& t : terms) {
    for (int v : t) {
      const Variable& var = m.variables[static_cast<std::size_t>(v)];
      HATTR_THROW_UNLESS(!var.factor || var.levels.size() >= 2, "{}: factor '{}' has one level ('{}'); a factor in the "
                         "{} effects needs at least 2 (leave it out of the formula)", data.source, var.name,
                         var.levels[0], part);
    }
  }
}

/// One random term's block, its grouping factor's levels the combinations seen in the data.
RandomBlock randomBlock(const DataTable& data, const ParsedFormula& formula, const RandomTerm& r,
                        const std::vector<Variable>& groups, const Model& m) {
  const std::size_t rows = static_cast<std::size_t>(m.y.size());
  RandomBlock b;
  b.group_name = termLabel(formula, r.group);  // "b:a" for a/b, as lme4 names it
  std::map<std::vector<int>, int> level_of;
  b.group_of_row.resize(rows);
  for (std::size_t row = 0; row < rows; ++row) {
    std::vector<int> key;
    for (int g : r.group) key.push_back(groups[static_cast<std::size_t>(g)].codes[row]);
    const auto [it, added] = level_of.emplace(key, static_cast<int>(level_of.size()));
    b.group_of_row[row] = it->second;
  }
  b.levels = level_of.size();
  // lme4's checks: a grouping needs 2 levels, fewer levels than observations, and fewer
  // random effects than observations.
  HATTR_THROW_UNLESS(b.levels >= 2, "{}: grouping factor '{}' has one level; a random effect needs at least 2 "
                     "(lme4: grouping factors must have > 1 sampled level)", data.source, b.group_name);
  HATTR_THROW_UNLESS(b.levels < rows, "{}: grouping factor '{}' has {} levels for {} rows; each level needs more than "
                     "one observation on average (lme4 refuses this too)", data.source, b.group_name, b.levels, rows);
  const Design effects = designMatrix(m.variables, r.intercept, r.terms);
  b.effects = effects.names;
  b.effects_matrix = effects.matrix;
  HATTR_THROW_UNLESS(rows > b.levels * b.size(), "{}: {} observations for {} random effects of '{}' ({} levels × {}); "
                     "the random effects and the residual variance cannot be told apart (lme4 refuses this too): "
                     "simplify the random term", data.source, rows, b.levels * b.size(), b.group_name, b.levels, b.size());
  return b;
}

/// The blocks in lme4's order (mkReTrms), a repeated grouping's name numbered, and each
/// block's place in theta with its lower bounds.
void orderBlocks(Model& m) {
  // When a later grouping has more levels: by decreasing levels, ties in reverse.
  bool reorder = false;
  for (std::size_t i = 1; i < m.blocks.size(); ++i) reorder = reorder || m.blocks[i].levels > m.blocks[i - 1].levels;
  if (reorder) {
    std::stable_sort(m.blocks.begin(), m.blocks.end(),
                     [](const RandomBlock& a, const RandomBlock& b) { return a.levels < b.levels; });
    std::reverse(m.blocks.begin(), m.blocks.end());
  }
  std::map<std::string, int> seen;
  for (RandomBlock& b : m.blocks) {
    const int n = seen[b.group_name]++;
    if (n > 0) b.group_name += fmt::format(".{}", n);
  }
  for (RandomBlock& b : m.blocks) {
    b.theta_offset = m.theta_size;
    const std::size_t r = b.size();
    for (std::size_t col = 0; col < r; ++col) {
      for (std::size_t row = col; row < r; ++row) {
        m.theta_lower.push_back(row == col ? 0.0 : -std::numeric_limits<double>::infinity());
      }
    }
    m.theta_size += r * (r + 1) / 2;
  }
}

}  // namespace

Model buildModel(const DataTable& data, const ParsedFormula& formula, const LmmOptions& options) {
  HATTR_THROW_UNLESS(!formula.random.empty(), "formula '{}': no random-effects term such as (1 | subject); a mixed model "
                     "needs one (use hattr anova for a fixed-effects model)", formula.text);
  Model m;
  m.formula = formula;
  const std::vector<Variable> groups = readModelVariables(data, formula, options, m);
  requireTwoLevels(data, m, formula.fixed, "fixed");
  for (const RandomTerm& r : formula.random) requireTwoLevels(data, m, r.terms, "random");
  m.fixed = designMatrix(m.variables, formula.intercept, formula.fixed);
  HATTR_THROW_UNLESS(m.fixed.matrix.cols() > 0, "formula '{}': no fixed effects; keep the intercept or name a column",
                     formula.text);
  m.dropped = dropDependentColumns(m.fixed);
  for (const RandomTerm& r : formula.random) m.blocks.push_back(randomBlock(data, formula, r, groups, m));
  orderBlocks(m);
  return m;
}

}  // namespace hattr::analysis::lmm
