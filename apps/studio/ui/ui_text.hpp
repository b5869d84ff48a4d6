#pragma once
/// Small helpers the studio's widgets share: library text to Qt, an exception's text, the
/// word-wrapped, selectable label every tab uses, plain prompts, the glyph picker's items, and a
/// profile in a few words. GUI thread only (wrappedLabel).

#include <QComboBox>
#include <QLabel>
#include <QRegularExpression>
#include <QString>
#include <algorithm>
#include <vector>
#include <exception>
#include <string>
#include <string_view>

#include "hattr/core/haptic_profile.hpp"
#include "hattr/guidance/strategy_catalog.hpp"
#include "hattr/sim/glyph.hpp"

namespace hattr::studio {

inline QString qs(const std::string& text) { return QString::fromStdString(text); }
inline QString qs(std::string_view text) { return QString::fromUtf8(text.data(), static_cast<qsizetype>(text.size())); }
inline QString what(const std::exception& e) { return QString::fromUtf8(e.what()); }

/// A word-wrapped label whose text can be selected (and copied).
inline QLabel* wrappedLabel(const QString& text = {}) {
  auto* label = new QLabel(text);
  label->setWordWrap(true);
  label->setTextInteractionFlags(Qt::TextSelectableByMouse);
  return label;
}

/// A prompt of the library's ("Training with ALPHA: trial 3 of 11", "Post-test: trial 1 of 3") as
/// a teacher reads it: each strategy's technical name as a whole word replaced by its plain name
/// ("Training with Guided pressure"), and a phase that opens it by what the learner does
/// ("Written alone: trial 1 of 3"). The patterns are made once.
inline QString plainPrompt(QString text) {
  struct Rule {
    QRegularExpression pattern;
    QString plain;
  };
  static const std::vector<Rule> rules = [] {
    std::vector<const guidance::StrategyInfo*> by_length;
    for (const auto& info : guidance::strategyCatalog()) by_length.push_back(&info);
    std::sort(by_length.begin(), by_length.end(), [](const auto* a, const auto* b) {
      return guidance::modeName(a->mode).size() > guidance::modeName(b->mode).size();
    });
    std::vector<Rule> made;
    for (const auto* info : by_length) {
      const QString name = QRegularExpression::escape(qs(guidance::modeName(info->mode)));
      made.push_back({QRegularExpression(QStringLiteral("(?<![A-Za-z-])") + name + QStringLiteral("(?![A-Za-z-])")),
                      qs(info->plain_name)});
    }
    for (const auto& [phase, plain] : {std::pair{"Baseline", "Before practice"}, std::pair{"Post-test", "Written alone"},
                                       std::pair{"Retention", "Written alone, days later"},
                                       std::pair{"Transfer", "A new letter"}}) {
      made.push_back({QRegularExpression(QStringLiteral("^") + QString::fromLatin1(phase) + QStringLiteral(":")),
                      QString::fromLatin1(plain) + QStringLiteral(":")});
    }
    return made;
  }();
  for (const Rule& rule : rules) text.replace(rule.pattern, rule.plain);
  return text;
}

/// Every built-in glyph as an item of `box`: by its character and name ("a   (small-a)", or the
/// name alone for a shape that is no character), the name as the item's data.
inline void addGlyphItems(QComboBox* box) {
  for (const sim::Glyph& glyph : sim::builtInGlyphs()) {
    const QString name = qs(glyph.name);
    box->addItem(glyph.character.empty() ? name : QStringLiteral("%1   (%2)").arg(qs(glyph.character), name), name);
  }
}

/// A profile in a few words: its samples, its length and how many have the pen down.
inline QString describeProfile(const HapticProfile& p) {
  return QObject::tr("%1 samples, %2 s, %3 with the pen down")
      .arg(p.size())
      .arg(p.duration_s(), 0, 'f', 2)
      .arg(p.penDownCount());
}

}  // namespace hattr::studio
