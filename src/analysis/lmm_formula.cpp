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

}  // namespace hattr::analysis::lmm
