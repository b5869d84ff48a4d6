// hattr-studio: the desktop testbed where a person records, trains and reviews
// (docs/studio.md).
#include <QApplication>
#include <QCommandLineParser>
#include <QTabWidget>
#include <QTimer>

#include <cstdio>

#include "ui/main_window.hpp"

namespace {

// The tab a name on the command line means, -1 for none.
int tabNamed(const QString& name) {
  const QStringList names{QStringLiteral("write"), QStringLiteral("record"), QStringLiteral("train"),
                          QStringLiteral("study"), QStringLiteral("review"), QStringLiteral("mentor"),
                          QStringLiteral("learners")};
  return static_cast<int>(names.indexOf(name.toLower()));
}

}  // namespace

int main(int argc, char** argv) {
  QApplication app(argc, argv);
  QApplication::setOrganizationName(QStringLiteral("hattr"));
  QApplication::setApplicationName(QStringLiteral("studio"));

  // --tab opens one tab first; --screenshot saves the window once it has drawn and quits (a
  // check of an install, pictures for the docs).
  QCommandLineParser parser;
  parser.setApplicationDescription(QStringLiteral("hattr studio: record, train and review on the virtual paper"));
  parser.addHelpOption();
  const QCommandLineOption tab_option(QStringLiteral("tab"),
                                      QStringLiteral("Open this tab: write, record, train, study, review, mentor, learners"),
                                      QStringLiteral("name"));
  const QCommandLineOption shot_option(QStringLiteral("screenshot"),
                                       QStringLiteral("Save the window as this PNG once it has drawn, then quit"),
                                       QStringLiteral("file"));
  parser.addOption(tab_option);
  parser.addOption(shot_option);
  parser.process(app);
  const int tab = parser.isSet(tab_option) ? tabNamed(parser.value(tab_option)) : -1;
  if (parser.isSet(tab_option) && tab < 0) {
    std::fprintf(stderr, "hattr-studio: --tab: expected write, record, train, study, review, mentor or learners, got \"%s\"\n",
                 parser.value(tab_option).toUtf8().constData());
    return 2;
  }

  hattr::studio::MainWindow window;
  if (tab >= 0) window.tabs()->setCurrentIndex(tab);
  window.fitToScreen();  // the size remembered or 1280 × 820, within the screen
  window.show();
  window.fitToScreen();  // again, now that the frame is known
  if (parser.isSet(shot_option)) {
    const QString file = parser.value(shot_option);
    QTimer::singleShot(1500, &window, [&window, file] {
      const bool saved = window.grab().save(file, "PNG");
      std::fprintf(saved ? stdout : stderr, "hattr-studio: %s %s\n", saved ? "saved" : "could not save",
                   file.toUtf8().constData());
      QApplication::exit(saved ? 0 : 1);
    });
  }
  return QApplication::exec();
}
