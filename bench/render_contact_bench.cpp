// Nanoseconds per contact query: proxy update, friction, texture lookup and height-field
// mesh, on a 512×512 paper-grain height field with texture, while the pen writes circles.
// Flat-paper contact (spring–damper only) in the same run for scale.
//   build/release/bench/bench_render_contact

#include <cmath>
#include <vector>

#include <benchmark/benchmark.h>

#include "hattr/render/flat_paper.hpp"
#include "hattr/core/world_renderer.hpp"
#include "hattr/render/paper_renderer.hpp"

namespace {

using namespace hattr;

/// Pen states along circles of 15 mm radius, one turn per second at 1 kHz, 0.5 mm deep.
std::vector<PenState> circlePath(const render::HeightField& relief) {
  std::vector<PenState> path(4096);
  for (std::size_t i = 0; i < path.size(); ++i) {
    const double t = static_cast<double>(i) * 1e-3;
    const double a = 2 * 3.141592653589793 * t;
    PenState& pen = path[i];
    pen.t_s = t;
    pen.p_WT = Vec3(0.015 * std::cos(a), 0.015 * std::sin(a), 0.0);
    pen.p_WT.z() = relief.heightAt(pen.p_WT.x(), pen.p_WT.y()) - 5e-4;
    pen.v_WT = Vec3(-0.094 * std::sin(a), 0.094 * std::cos(a), 0.0);
  }
  return path;
}

template <typename Renderer>
void runQueries(benchmark::State& state, Renderer& renderer, const std::vector<PenState>& path) {
  ContactForces out;
  std::size_t i = 0;
  for (auto _ : state) {
    renderer.render(path[i], 1e-3, out);
    benchmark::DoNotOptimize(out);
    i = (i + 1) & (path.size() - 1);
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_ContactQuery_HeightField512_Texture(benchmark::State& state) {
  render::PaperParams params;  // defaults: friction with texture σ = 0.03
  render::PaperRenderer paper(params, render::HeightField::paperGrain(0.16, 512, 1e-5, 5e-4, 2));
  const auto path = circlePath(paper.relief());
  runQueries(state, paper, path);
}

void BM_ContactQuery_FlatSpringDamper(benchmark::State& state) {
  render::FlatPaper paper;
  const auto path = circlePath(render::HeightField{});
  runQueries(state, paper, path);
}

BENCHMARK(BM_ContactQuery_HeightField512_Texture)->Repetitions(5)->ReportAggregatesOnly(true);
BENCHMARK(BM_ContactQuery_FlatSpringDamper)->Repetitions(5)->ReportAggregatesOnly(true);

}  // namespace
