// The formula of a linear mixed model and its design matrices, with R's conventions
// (lmm_model.hpp, docs/analysis.md).

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

// ---- Tokens -------------------------------------------------------------------------

struct Token {
  enum Kind { kName, kNumber, kSymbol, kEnd } kind;
  std::string text;
  std::size_t position;
};

bool isNameChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '.'; }

std::vector<Token> tokenize(std::string_view text) {
  std::vector<Token> tokens;
  for (std::size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (std::isspace(static_cast<unsigned char>(c)) != 0) {
      ++i;
    } else if (c == '`') {  // a quoted name: `my column`
      const std::size_t end = text.find('`', i + 1);
      HATTR_THROW_UNLESS(end != std::string_view::npos, "formula '{}': a ` at character {} is not closed", text, i + 1);
      tokens.push_back({Token::kName, std::string(text.substr(i + 1, end - i - 1)), i});
      i = end + 1;
    } else if (isNameChar(c)) {
      std::size_t end = i;
      while (end < text.size() && isNameChar(text[end])) ++end;
      const std::string word(text.substr(i, end - i));
      const bool number = std::all_of(word.begin(), word.end(), [](char d) { return std::isdigit(static_cast<unsigned char>(d)); });
      tokens.push_back({number ? Token::kNumber : Token::kName, word, i});
      i = end;
    } else if (c == '|' && i + 1 < text.size() && text[i + 1] == '|') {
      tokens.push_back({Token::kSymbol, "||", i});
      i += 2;
    } else if (std::string_view("~+-*:/|()").find(c) != std::string_view::npos) {
      tokens.push_back({Token::kSymbol, std::string(1, c), i});
      ++i;
    } else {
      throw InputError(fmt::format("formula '{}': unexpected '{}' at character {}; expected column names, "
                                   "numbers 0 and 1, and ~ + - * : / | || ( )", text, c, i + 1));
    }
  }
  tokens.push_back({Token::kEnd, "", text.size()});
  return tokens;
}

// ---- Terms --------------------------------------------------------------------------

/// A sum of terms; intercept markers ("1", "0", "-1") are kept apart.
struct Terms {
  std::vector<Term> terms;
  int intercept = -1;  // -1 not said, 0 removed, 1 added
};

void addTerm(std::vector<Term>& terms, const Term& term) {
  if (std::find(terms.begin(), terms.end(), term) == terms.end()) terms.push_back(term);
}

Term unite(const Term& a, const Term& b) {
  Term out;
  std::set_union(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

/// a:b — every term of a with every term of b.
std::vector<Term> interact(const std::vector<Term>& a, const std::vector<Term>& b) {
  std::vector<Term> out;
  for (const Term& x : a) {
    for (const Term& y : b) addTerm(out, unite(x, y));
  }
  return out;
}

/// Recursive-descent parser of R's formula language, the subset lme4 formulas use.
class Parser {
 public:
  explicit Parser(std::string_view text) : text_(text), tokens_(tokenize(text)) {}

  ParsedFormula parse() {
    ParsedFormula f;
    f.text = std::string(text_);
    HATTR_THROW_UNLESS(peek().kind == Token::kName, "formula '{}': expected the response column first, got '{}'", text_,
                       describe(peek()));
    f.response = next().text;
    expect("~");
    parseSum(f);
    HATTR_THROW_UNLESS(peek().kind == Token::kEnd, "formula '{}': unexpected '{}' at character {}", text_, peek().text,
                       peek().position + 1);
    HATTR_THROW_UNLESS(std::find(variables_.begin(), variables_.end(), f.response) == variables_.end(),
                       "formula '{}': the response '{}' is also a predictor", text_, f.response);
    renumberFixedFirst(f);
    // R orders terms by degree, keeping their order within a degree.
    std::stable_sort(f.fixed.begin(), f.fixed.end(), [](const Term& a, const Term& b) { return a.size() < b.size(); });
    return f;
  }

  /// lme4 builds X from the fixed part alone: its variables come first, in the order they
  /// appear there (which orders the names of interactions: "aB:x"), then the others.
  void renumberFixedFirst(ParsedFormula& f) const {
    std::vector<int> order = fixed_order_;
    for (int v = 0; v < static_cast<int>(variables_.size()); ++v) {
      if (std::find(order.begin(), order.end(), v) == order.end()) order.push_back(v);
    }
    std::vector<int> index(variables_.size());
    for (std::size_t k = 0; k < order.size(); ++k) {
      index[static_cast<std::size_t>(order[k])] = static_cast<int>(k);
      f.variables.push_back(variables_[static_cast<std::size_t>(order[k])]);
    }
    const auto remap = [&](Term& t, bool sort) {
      for (int& v : t) v = index[static_cast<std::size_t>(v)];
      if (sort) std::sort(t.begin(), t.end());
    };
    for (Term& t : f.fixed) remap(t, true);
    for (RandomTerm& r : f.random) {
      for (Term& t : r.terms) remap(t, true);
      remap(r.group, false);  // the grouping keeps its written order, as lme4 names it
    }
  }

 private:
  const Token& peek() const { return tokens_[at_]; }
  const Token& next() { return tokens_[at_++]; }
  bool accept(std::string_view symbol) {
    if (peek().kind != Token::kSymbol || peek().text != symbol) return false;
    ++at_;
    return true;
  }
  void expect(std::string_view symbol) {
    HATTR_THROW_UNLESS(accept(symbol), "formula '{}': expected '{}' at character {}, got '{}'", text_, symbol,
                       peek().position + 1, describe(peek()));
  }
  static std::string describe(const Token& t) { return t.kind == Token::kEnd ? "the end" : t.text; }

  int variable(const std::string& name) {
    const auto it = std::find(variables_.begin(), variables_.end(), name);
    if (it != variables_.end()) {
      const int v = static_cast<int>(it - variables_.begin());
      if (in_fixed_ && std::find(fixed_order_.begin(), fixed_order_.end(), v) == fixed_order_.end()) fixed_order_.push_back(v);
      return v;
    }
    variables_.push_back(name);
    const int v = static_cast<int>(variables_.size() - 1);
    if (in_fixed_ && std::find(fixed_order_.begin(), fixed_order_.end(), v) == fixed_order_.end()) fixed_order_.push_back(v);
    return v;
  }

  /// Is the parenthesis at the cursor a random-effects term "( ... | ... )"?
  bool atRandomTerm() const {
    if (peek().kind != Token::kSymbol || peek().text != "(") return false;
    int depth = 0;
    for (std::size_t i = at_; tokens_[i].kind != Token::kEnd; ++i) {
      const std::string& s = tokens_[i].text;
      if (tokens_[i].kind != Token::kSymbol) continue;
      if (s == "(") ++depth;
      if (s == ")" && --depth == 0) return false;
      if ((s == "|" || s == "||") && depth == 1) return true;
    }
    return false;
  }

  /// The right-hand side: fixed terms and random-effects terms.
  void parseSum(ParsedFormula& f) {
    const Terms t = parseSumOf(&f);
    f.fixed = t.terms;
    f.intercept = t.intercept != 0;
  }

  /// A sum: items joined by + or −, as R reads them ("- 1" and "+ 0" remove the intercept,
  /// "- 0" and "+ 1" keep it); at the top level (`f` given) an item may be a random term.
  Terms parseSumOf(ParsedFormula* f) {
    Terms out;
    bool minus = accept("-");
    for (;;) {
      if (minus) {
        HATTR_THROW_UNLESS(peek().kind == Token::kNumber && (peek().text == "1" || peek().text == "0"),
                           "formula '{}': only 1 or 0 can be subtracted (character {}), got '{}'", text_,
                           peek().position + 1, describe(peek()));
        out.intercept = next().text == "0" ? 1 : 0;
      } else if (f != nullptr && atRandomTerm()) {
        parseRandomTerm(*f);
      } else {
        if (f != nullptr) in_fixed_ = true;  // nested sums (parentheses) keep the flag
        const Terms t = parseProduct();
        if (f != nullptr) in_fixed_ = false;
        if (t.intercept >= 0) out.intercept = t.intercept;
        for (const Term& term : t.terms) addTerm(out.terms, term);
      }
      if (accept("+")) {
        minus = false;
      } else if (accept("-")) {
        minus = true;
      } else {
        return out;
      }
    }
  }

  void parseRandomTerm(ParsedFormula& f) {
    const std::size_t where = peek().position + 1;
    expect("(");
    Terms lhs = parseExpression();
    const bool independent = accept("||");
    if (!independent) expect("|");
    std::vector<Term> groups = parseGroup();
    expect(")");
    HATTR_THROW_UNLESS(lhs.intercept != 0 || !lhs.terms.empty(), "formula '{}': the random term at character {} has no effects",
                       text_, where);
    for (const Term& group : groups) {
      RandomTerm r;
      r.group = group;
      r.intercept = lhs.intercept != 0;
      r.terms = lhs.terms;
      if (!independent) {
        f.random.push_back(r);
        continue;
      }
      // (1 + x || g) is (1 | g) + (0 + x | g): one term an effect.
      if (r.intercept) f.random.push_back(RandomTerm{true, {}, group});
      for (const Term& t : lhs.terms) f.random.push_back(RandomTerm{false, {t}, group});
    }
  }

  /// A grouping factor: "g", "a:b", or "a/b" (a, and b within a: "b:a" and "a").
  std::vector<Term> parseGroup() {
    std::vector<std::vector<int>> chain{{parseGroupName()}};
    while (accept(":")) chain.back().push_back(parseGroupName());
    while (accept("/")) chain.push_back({parseGroupName()});
    if (chain.size() == 1) return {chain[0]};
    HATTR_THROW_UNLESS(chain.size() == 2, "formula '{}': nest one level with '/' (a/b); for deeper nesting write "
                       "the groupings out: (1 | a) + (1 | a:b) + (1 | a:b:c)", text_);
    // lme4 names the inner factor first: (1 | a/b) is (1 | b:a) + (1 | a).
    std::vector<Term> out;
    for (std::size_t depth = chain.size(); depth-- > 0;) {
      Term group;
      for (std::size_t k = depth + 1; k-- > 0;) group.insert(group.end(), chain[k].begin(), chain[k].end());
      out.push_back(group);
    }
    return out;
  }
  int parseGroupName() {
    HATTR_THROW_UNLESS(peek().kind == Token::kName, "formula '{}': expected a grouping column at character {}, got '{}'",
                       text_, peek().position + 1, describe(peek()));
    return variable(next().text);
  }

  // expression := a sum (inside parentheses and random terms)
  Terms parseExpression() { return parseSumOf(nullptr); }

  // product := interaction ('*' interaction)*;  a*b = a + b + a:b
  Terms parseProduct() {
    Terms out = parseInteraction();
    while (accept("*")) {
      const Terms right = parseInteraction();
      std::vector<Term> terms = out.terms;
      for (const Term& t : right.terms) addTerm(terms, t);
      for (const Term& t : interact(out.terms, right.terms)) addTerm(terms, t);
      out.terms = terms;
    }
    return out;
  }

  // interaction := primary (':' primary)*
  Terms parseInteraction() {
    Terms out = parsePrimary();
    while (accept(":")) {
      const Terms right = parsePrimary();
      HATTR_THROW_UNLESS(out.intercept < 0 && right.intercept < 0, "formula '{}': 0 or 1 cannot be part of an interaction",
                         text_);
      out.terms = interact(out.terms, right.terms);
    }
    return out;
  }

  // primary := name | 0 | 1 | '(' expression ')'
  Terms parsePrimary() {
    if (accept("(")) {
      Terms inner = parseExpression();
      expect(")");
      return inner;
    }
    const Token& t = next();
    if (t.kind == Token::kNumber && (t.text == "0" || t.text == "1")) return Terms{{}, t.text == "1" ? 1 : 0};
    HATTR_THROW_UNLESS(t.kind == Token::kName, "formula '{}': expected a column name at character {}, got '{}'", text_,
                       t.position + 1, describe(t));
    return Terms{{Term{variable(t.text)}}, -1};
  }

  std::string_view text_;
  std::vector<Token> tokens_;
  std::size_t at_ = 0;
  std::vector<std::string> variables_;
  bool in_fixed_ = false;          // parsing a fixed term of the top level
  std::vector<int> fixed_order_;   // variables in the order the fixed part first names them
};

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

std::string joinNames(const std::vector<std::string>& names, const char* separator) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : separator) + n;
  return out;
}

}  // namespace

ParsedFormula parseFormula(std::string_view text) { return Parser(text).parse(); }

std::string termLabel(const ParsedFormula& formula, const Term& term) {
  std::vector<std::string> names;
  for (int v : term) names.push_back(formula.variables[static_cast<std::size_t>(v)]);
  return joinNames(names, ":");
}

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

Model buildModel(const DataTable& data, const ParsedFormula& formula, const LmmOptions& options) {
  HATTR_THROW_UNLESS(!formula.random.empty(), "formula '{}': no random-effects term such as (1 | subject); a mixed model "
                     "needs one (use hattr anova for a fixed-effects model)", formula.text);
  Model m;
  m.formula = formula;

  // The response and the variables, all of one length.
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

  // Factors in the effects, fixed or random, need two levels (R's contrasts do).
  const auto twoLevels = [&](const std::vector<Term>& terms, const char* part) {
    for (const Term& t : terms) {
      for (int v : t) {
        const Variable& var = m.variables[static_cast<std::size_t>(v)];
        HATTR_THROW_UNLESS(!var.factor || var.levels.size() >= 2, "{}: factor '{}' has one level ('{}'); a factor in the "
                           "{} effects needs at least 2 (leave it out of the formula)", data.source, var.name,
                           var.levels[0], part);
      }
    }
  };
  twoLevels(formula.fixed, "fixed");
  for (const RandomTerm& r : formula.random) twoLevels(r.terms, "random");
  m.fixed = designMatrix(m.variables, formula.intercept, formula.fixed);
  HATTR_THROW_UNLESS(m.fixed.matrix.cols() > 0, "formula '{}': no fixed effects; keep the intercept or name a column",
                     formula.text);
  m.dropped = dropDependentColumns(m.fixed);

  // Random-effects blocks, each grouping factor's levels the combinations seen in the data.
  for (const RandomTerm& r : formula.random) {
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
    m.blocks.push_back(std::move(b));
  }
  // lme4's order (mkReTrms): when a later grouping has more levels, by decreasing levels,
  // ties in reverse.
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
  return m;
}

}  // namespace hattr::analysis::lmm
