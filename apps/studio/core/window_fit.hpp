#pragma once
/// The main window's first size on a screen: as wanted, but never larger than the screen's
/// available area less the window's frame, so the status bar is on the screen (a 1280 × 800
/// laptop with a panel, a 1024 × 680 lab screen). GUI-free: tested without a screen.

#include <QSize>
#include <algorithm>

namespace hattr::studio {

/// The studio's size when nothing is remembered.
inline constexpr QSize kPreferredWindowSize(1280, 820);

/// `wanted` within `available` (the screen's area without panels) less `frame` (title bar and
/// borders: width and height they add), and no smaller than `minimum`.
[[nodiscard]] inline QSize fitWindow(QSize wanted, QSize available, QSize frame, QSize minimum) {
  const QSize most = available - frame;
  return {std::max(minimum.width(), std::min(wanted.width(), most.width())),
          std::max(minimum.height(), std::min(wanted.height(), most.height()))};
}

}  // namespace hattr::studio
