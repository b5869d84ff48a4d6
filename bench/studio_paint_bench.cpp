// What one frame of the studio's views costs the GUI thread: the top view (PaperView) and the
// 3-D view (PenSceneView), each painted into an image as Qt paints a widget, with the default
// paper (its grain relief), a 1300-point trail, the reference and a tilted pen; and the 3-D
// view's mesh, drawn again only on a resize or a new paper. Offscreen (Qt's raster engine, as
// on X11 without the server's copy to the screen).
//   build/release/bench/bench_studio_paint

#include <QApplication>
#include <QImage>
#include <QPainter>
#include <QPolygonF>
#include <cmath>
#include <numbers>

#include <benchmark/benchmark.h>

#include "hattr/session/trial.hpp"
#include "ui/paper_view.hpp"
#include "ui/pen_scene_view.hpp"
#include "ui/trail_drawing.hpp"

namespace {

using namespace hattr;
using namespace hattr::studio;

/// The two views over the studio's default paper, with a figure-eight written on it.
struct Views {
  session::TrialEnvironment environment{"sim://pen", render::WorldConfig{}, 1000.0};
  PaperView top;
  PenSceneView scene{&top};

  Views() {
    const DeviceLimits& l = environment.limits();
    top.resize(640, 480);
    scene.resize(400, 480);
    top.setPaper(environment.paper().relief(), l.workspace_min_m.x(), l.workspace_min_m.y(), l.workspace_max_m.x(),
                 l.workspace_max_m.y());
    scene.setPaper(environment.paper().relief(), l.workspace_min_m.x(), l.workspace_min_m.y(), l.workspace_max_m.x(),
                   l.workspace_max_m.y());
    Sample s;
    s.pen_down = s.in_contact = true;
    for (int i = 0; i < 1300; ++i) {
      const double a = 2.0 * std::numbers::pi * i / 1300.0;
      s.t_s = i * 1e-3;
      s.p_WT = Vec3(0.03 * std::sin(a), 0.015 * std::sin(2.0 * a), 0.0);
      top.trail().append(s);
      top.reference().append(s);
    }
    s.tilt_altitude_rad = 50.0 * std::numbers::pi / 180.0;
    s.tilt_azimuth_rad = 0.5;
    top.setPen(s);
  }
};

Views& views() {
  static Views v;
  return v;
}

void paint(benchmark::State& state, QWidget& widget) {
  QImage image(widget.size(), QImage::Format_ARGB32_Premultiplied);
  widget.render(&image);  // the 3-D view's mesh is drawn once, here
  for (auto _ : state) {
    widget.render(&image);
    benchmark::DoNotOptimize(image.constBits());
  }
}

void BM_TopViewFrame(benchmark::State& state) { paint(state, views().top); }
void BM_SceneViewFrame(benchmark::State& state) { paint(state, views().scene); }

// A resize: the mesh drawn again (two sizes in turn, so each render redraws it).
void BM_SceneViewMesh(benchmark::State& state) {
  PenSceneView& scene = views().scene;
  QImage image(scene.size(), QImage::Format_ARGB32_Premultiplied);
  bool wide = false;
  for (auto _ : state) {
    scene.resize(wide ? 400 : 401, 480);
    wide = !wide;
    scene.render(&image);
    benchmark::DoNotOptimize(image.constBits());
  }
}

// The trail and the reference alone, over the top view's mapping: as the views draw them now
// (drawTrailStrokes: round-capped segments, sub-pixel steps skipped), and as they did before
// (one polyline per stroke, round joins): the baseline, in the same run.
void drawTrails(benchmark::State& state, bool as_segments) {
  PaperView& top = views().top;
  QImage image(top.size(), QImage::Format_ARGB32_Premultiplied);
  const auto to_pixels = [&](const Eigen::Vector2d& p) { return top.mapping().toWidget(p.x(), p.y()); };
  for (auto _ : state) {
    image.fill(Qt::white);
    QPainter painter(&image);
    painter.setRenderHint(QPainter::Antialiasing);
    // The widths the top view uses: the reference 3 px, the trail 2.5 px.
    for (const auto& [trail, width] : {std::pair{&top.reference(), 3.0}, std::pair{&top.trail(), 2.5}}) {
      if (as_segments) {
        drawTrailStrokes(painter, *trail, Qt::black, width, to_pixels);
        continue;
      }
      painter.setPen(QPen(Qt::black, width, Qt::SolidLine, Qt::RoundCap, Qt::RoundJoin));
      for (const auto& stroke : trail->strokes()) {
        QPolygonF polyline;
        for (const auto& p : stroke) polyline << to_pixels(p);
        painter.drawPolyline(polyline);
      }
    }
    benchmark::DoNotOptimize(image.constBits());
  }
}
void BM_TrailsAsSegments(benchmark::State& state) { drawTrails(state, true); }
void BM_TrailsAsPolylines(benchmark::State& state) { drawTrails(state, false); }

BENCHMARK(BM_TrailsAsSegments)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TrailsAsPolylines)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TopViewFrame)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SceneViewFrame)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SceneViewMesh)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  qputenv("QT_QPA_PLATFORM", "offscreen");
  QApplication app(argc, argv);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
