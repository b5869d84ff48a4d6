#pragma once
/// Small helpers the studio's widgets share: library text to Qt, an exception's text, the
/// word-wrapped, selectable label every tab uses, and a profile in a few words. GUI thread only (wrappedLabel).

#include <QLabel>
#include <QString>
#include <exception>
#include <string>
#include <string_view>

#include "hattr/core/haptic_profile.hpp"

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

/// A profile in a few words: its samples, its length and how many have the pen down.
inline QString describeProfile(const HapticProfile& p) {
  return QObject::tr("%1 samples, %2 s, %3 with the pen down")
      .arg(p.size())
      .arg(p.duration_s(), 0, 'f', 2)
      .arg(p.penDownCount());
}

}  // namespace hattr::studio
