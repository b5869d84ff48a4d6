#pragma once
// What the study reports share (study_report.cpp, design_report.cpp): numbers as text, a
// table and a document rendered to Markdown and HTML at once, and the files written.

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "hattr/analysis/studentized_range.hpp"
#include "hattr/io/profile_csv.hpp"
#include "svg_plot_internal.hpp"

namespace hattr::report::detail {

/// Mean and the half-width of its 95 % confidence interval (Student's t; NaN below 2 values).
inline std::pair<double, double> meanWithCi(const std::vector<double>& values) {
  const auto n = static_cast<double>(values.size());
  double mean = 0.0;
  for (const double v : values) mean += v / n;
  if (values.size() < 2) return {mean, std::numeric_limits<double>::quiet_NaN()};
  double ss = 0.0;
  for (const double v : values) ss += (v - mean) * (v - mean);
  return {mean, analysis::studentTQuantile(0.975, n - 1.0) * std::sqrt(ss / (n - 1.0) / n)};
}

inline std::string p(double v) { return std::isfinite(v) ? (v < 0.001 ? "< 0.001" : fmt::format("{:.3f}", v)) : ""; }
/// "p = 0.042" or "p < 0.001", for sentences.
inline std::string pIs(double v) { return v < 0.001 ? "p < 0.001" : fmt::format("p = {:.3f}", v); }
inline std::string g(double v) { return std::isfinite(v) ? fmt::format("{:.4g}", v) : ""; }

/// A table as Markdown and as HTML at once.
struct Table {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  std::string markdown() const {
    std::string out = "| " + fmt::format("{}", fmt::join(header, " | ")) + " |\n|";
    for (std::size_t i = 0; i < header.size(); ++i) out += "---|";
    out += "\n";
    for (const auto& r : rows) out += "| " + fmt::format("{}", fmt::join(r, " | ")) + " |\n";
    return out;
  }
  std::string html() const {
    std::string out = "<table><tr>";
    for (const auto& h : header) out += "<th>" + escape(h) + "</th>";
    out += "</tr>\n";
    for (const auto& r : rows) {
      out += "<tr>";
      for (const auto& c : r) out += "<td>" + escape(c) + "</td>";
      out += "</tr>\n";
    }
    return out + "</table>\n";
  }
};

/// A document built once, rendered to both Markdown and HTML.
class Document {
 public:
  void heading(const std::string& text, int level = 2) {
    md_ += fmt::format("\n{} {}\n\n", std::string(static_cast<std::size_t>(level), '#'), text);
    html_ += fmt::format("<h{0}>{1}</h{0}>\n", level, escape(text));
  }
  void paragraph(const std::string& text) {
    md_ += text + "\n\n";
    html_ += "<p>" + escape(text) + "</p>\n";
  }
  void list(const std::vector<std::string>& items) {
    html_ += "<ul>";
    for (const auto& i : items) {
      md_ += "- " + i + "\n";
      html_ += "<li>" + escape(i) + "</li>";
    }
    md_ += "\n";
    html_ += "</ul>\n";
  }
  void table(const Table& t) {
    md_ += t.markdown() + "\n";
    html_ += t.html();
  }
  void figure(const std::string& name, const std::string& svg, const std::string& caption,
              std::map<std::string, std::string>& files) {
    files["figures/" + name + ".svg"] = svg;
    md_ += fmt::format("![{}](figures/{}.svg)\n\n*{}*\n\n", caption, name, caption);
    // The figure's id is its file's name: a link can point at it, and a test finds its file.
    html_ += fmt::format("<figure id=\"{}\">{}<figcaption>{}</figcaption></figure>\n", name, svg, escape(caption));
  }
  const std::string& markdown() const { return md_; }
  const std::string& html() const { return html_; }

 private:
  std::string md_;
  std::string html_;
};

/// Writes OUT/report.md, OUT/report.html (self-contained: the figures inline) and `files`
/// (figures/NAME.svg) into OUT, replacing earlier ones.
inline void writeReportFiles(const std::filesystem::path& out, const std::string& title, const Document& doc,
                             const std::map<std::string, std::string>& files) {
  std::filesystem::create_directories(out / "figures");
  for (const auto& [name, text] : files) hattr::writeFileAtomically(out / name, text, hattr::Overwrite::kReplace);
  hattr::writeFileAtomically(out / "report.md", doc.markdown(), hattr::Overwrite::kReplace);
  const std::string html = fmt::format(
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title>\n<style>"
      "body{{font-family:sans-serif;max-width:1000px;margin:2em auto;color:#222}} table{{border-collapse:collapse;margin:0.5em 0}}"
      "td,th{{border:1px solid #ccc;padding:3px 8px;text-align:right}} th{{background:#f2f2f2}} figure{{margin:1em 0}}"
      "figcaption{{color:#555;font-size:0.9em}}</style></head><body>\n{}</body></html>\n",
      escape(title), doc.html());
  hattr::writeFileAtomically(out / "report.html", html, hattr::Overwrite::kReplace);
}

}  // namespace hattr::report::detail
