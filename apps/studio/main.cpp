// hattr-studio: the desktop testbed where a person records, trains and reviews
// (docs/studio.md).
#include <QApplication>

#include "ui/main_window.hpp"

int main(int argc, char** argv) {
  QApplication app(argc, argv);
  QApplication::setOrganizationName(QStringLiteral("hattr"));
  QApplication::setApplicationName(QStringLiteral("studio"));
  hattr::studio::MainWindow window;
  window.fitToScreen();  // the size remembered or 1280 × 820, within the screen
  window.show();
  window.fitToScreen();  // again, now that the frame is known
  return QApplication::exec();
}
