// hattr-studio: the desktop testbed where a person records, trains and reviews
// (docs/studio.md).
#include <QApplication>

#include "ui/main_window.hpp"

int main(int argc, char** argv) {
  QApplication app(argc, argv);
  QApplication::setOrganizationName(QStringLiteral("hattr"));
  QApplication::setApplicationName(QStringLiteral("studio"));
  hattr::studio::MainWindow window;
  window.resize(1280, 820);
  window.show();
  return QApplication::exec();
}
