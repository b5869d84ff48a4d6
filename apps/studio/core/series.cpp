#include "core/series.hpp"

#include <algorithm>

namespace hattr::studio {

void Trail::append(const Sample& sample) {
  if (!sample.pen_down) {
    pen_was_down_ = false;
    return;
  }
  if (!pen_was_down_ || strokes_.empty()) strokes_.emplace_back();
  pen_was_down_ = true;
  strokes_.back().emplace_back(sample.p_WT.x(), sample.p_WT.y());
  ++points_;
  // Over the limit: forget the oldest strokes (never the one being drawn).
  while (points_ > max_points_ && strokes_.size() > 1) {
    points_ -= strokes_.front().size();
    strokes_.erase(strokes_.begin());
  }
}

void Trail::assign(const HapticProfile& profile, std::size_t begin, std::size_t end) {
  clear();
  end = std::min(end, profile.size());
  for (std::size_t i = begin; i < end; ++i) append(profile[i]);
  pen_was_down_ = false;
}

void Trail::clear() {
  strokes_.clear();
  points_ = 0;
  pen_was_down_ = false;
}

void ForceSeries::append(double t, const Vec3& f_W) {
  t_s.push_back(t);
  fx_N.push_back(f_W.x());
  fy_N.push_back(f_W.y());
  fz_N.push_back(f_W.z());
}

void ForceSeries::clear() {
  t_s.clear();
  fx_N.clear();
  fy_N.clear();
  fz_N.clear();
}

ForceSeries ForceSeries::fromProfile(const HapticProfile& profile, std::size_t max_points, double t_offset_s) {
  ForceSeries series;
  if (profile.empty()) return series;
  const std::size_t stride =
      std::max<std::size_t>(1, (profile.size() + max_points - 1) / std::max<std::size_t>(max_points, 1));
  for (std::size_t i = 0; i < profile.size(); i += stride) {
    series.append(profile[i].t_s + t_offset_s, profile[i].f_user_W);
  }
  // Always end on the last sample, so the series spans the whole profile.
  if ((profile.size() - 1) % stride != 0)
    series.append(profile.samples().back().t_s + t_offset_s, profile.samples().back().f_user_W);
  return series;
}

std::pair<double, double> ForceSeries::forceRange() const noexcept {
  if (empty()) return {0.0, 0.0};
  double lo = fx_N.front();
  double hi = lo;
  for (const auto* channel : {&fx_N, &fy_N, &fz_N}) {
    const auto [min_it, max_it] = std::minmax_element(channel->begin(), channel->end());
    lo = std::min(lo, *min_it);
    hi = std::max(hi, *max_it);
  }
  return {lo, hi};
}

void Playback::load(const HapticProfile* profile) {
  profile_ = profile;
  playing_ = false;
  paused_at_t_s_ = 0.0;
}

void Playback::play(double now_s) {
  if (!loaded()) return;
  if (finished(now_s)) paused_at_t_s_ = 0.0;  // from the start again
  started_at_s_ = now_s - paused_at_t_s_ / speed_;
  playing_ = true;
}

void Playback::pause(double now_s) {
  paused_at_t_s_ = time_s(now_s);
  playing_ = false;
}

void Playback::rewind() {
  playing_ = false;
  paused_at_t_s_ = 0.0;
}

double Playback::time_s(double now_s) const noexcept {
  if (!loaded()) return 0.0;
  const double t = playing_ ? (now_s - started_at_s_) * speed_ : paused_at_t_s_;
  return std::clamp(t, 0.0, profile_->samples().back().t_s);
}

std::size_t Playback::indexAt(double t_s) const noexcept {
  if (!loaded()) return 0;
  const auto& samples = profile_->samples();
  const auto it =
      std::upper_bound(samples.begin(), samples.end(), t_s, [](double t, const Sample& s) { return t < s.t_s; });
  return it == samples.begin() ? 0 : static_cast<std::size_t>(it - samples.begin()) - 1;
}

bool Playback::finished(double now_s) const noexcept {
  if (!loaded()) return true;
  const double t = playing_ ? (now_s - started_at_s_) * speed_ : paused_at_t_s_;
  return t >= profile_->samples().back().t_s;
}

}  // namespace hattr::studio
