#pragma once
/// Small helpers the studio's widgets share: library text to Qt, an exception's text, the
/// word-wrapped, selectable label every tab uses, the glyph picker's items, and a
/// profile in a few words. GUI thread only (wrappedLabel).

#include <QComboBox>
#include <QLabel>
#include <QString>
#include <exception>
#include <string>
#include <string_view>

#include "hattr/core/haptic_profile.hpp"
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
