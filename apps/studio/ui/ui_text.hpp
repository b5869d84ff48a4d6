#pragma once
/// Small helpers the studio's widgets share: library text to Qt, an exception's text, the
/// word-wrapped, selectable label every tab uses, and a profile in a few words. GUI thread only (wrappedLabel).

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

/// `text` with each strategy's technical name ("PCONTROL", "MENTOR-FORCE") as a whole word
/// replaced by its plain name ("Guided path"): the library's prompts, as a teacher reads them.
inline QString plainStrategyNames(QString text) {
  std::vector<const guidance::StrategyInfo*> by_length;
  for (const auto& info : guidance::strategyCatalog()) by_length.push_back(&info);
  std::sort(by_length.begin(), by_length.end(), [](const auto* a, const auto* b) {
    return guidance::modeName(a->mode).size() > guidance::modeName(b->mode).size();
  });
  for (const auto* info : by_length) {
    const QString name = QRegularExpression::escape(qs(guidance::modeName(info->mode)));
    text.replace(QRegularExpression(QStringLiteral("(?<![A-Za-z-])") + name + QStringLiteral("(?![A-Za-z-])")),
                 qs(info->plain_name));
  }
  return text;
}

/// A profile in a few words: its samples, its length and how many have the pen down.
inline QString describeProfile(const HapticProfile& p) {
  return QObject::tr("%1 samples, %2 s, %3 with the pen down")
      .arg(p.size())
      .arg(p.duration_s(), 0, 'f', 2)
      .arg(p.penDownCount());
}

}  // namespace hattr::studio
