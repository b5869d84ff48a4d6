#include "cli_common.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <sstream>

#include <fmt/format.h>

#include "hattr/core/error.hpp"
#include "hattr/io/profile_csv.hpp"

namespace hattr::cli {

std::string profileSummaryText(const HapticProfile& profile) {
  const ProfileMetadata& meta = profile.metadata();
  std::string text = fmt::format(
      "samples     {} ({} pen down)\nduration    {:.4f} s\nrate        {:.2f} Hz measured, {} Hz nominal\n",
      profile.size(), profile.penDownCount(), profile.duration_s(), profile.measuredRate_hz(),
      meta.nominal_rate_hz);
  text += fmt::format("subject     {}\nskill       {}\ndevice      {}\nsource      {}\ncreated     {}\n",
                      meta.subject, meta.skill, meta.device, meta.source, meta.created_utc);
  for (const auto& [key, value] : meta.extra) text += fmt::format("{:<11} {}\n", key, value);
  text += fmt::format("\n{:<10} {:>8} {:>14} {:>14}\n", "channel", "unit", "min", "max");
  for (const auto& info : allChannels()) {
    if (!profile.hasChannel(info.channel) || profile.empty()) continue;
    const ChannelRange range = profile.range(info.channel);
    text += fmt::format("{:<10} {:>8} {:>14.6g} {:>14.6g}\n", info.name, info.unit, range.min, range.max);
  }
  return text;
}

void printJson(const nlohmann::json& json) { std::cout << json.dump(2) << '\n'; }

namespace {

/// The folder must be writable; a missing one (when it may be, the writer creates it) must
/// have a writable folder above it. Nothing is created here: a refused command leaves nothing.
void checkWritableFolder(const std::filesystem::path& folder, const std::filesystem::path& for_output, bool may_be_missing) {
  namespace fs = std::filesystem;
  fs::path dir = folder.empty() ? fs::path(".") : folder;
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) {
    throw InputError(fmt::format("{}: expected a folder for {}, got a file", dir.string(), for_output.string()));
  }
  if (!fs::exists(dir, ec)) {
    HATTR_THROW_UNLESS(may_be_missing, "{}: no such folder (for {})", dir.string(), for_output.string());
    dir = fs::absolute(dir, ec);
    while (!fs::exists(dir, ec) && dir.has_parent_path() && dir.parent_path() != dir) dir = dir.parent_path();
    HATTR_THROW_UNLESS(fs::is_directory(dir, ec), "{}: cannot be created under {} (a file)", folder.string(),
                       dir.string());
  }
  HATTR_THROW_UNLESS(::access(dir.c_str(), W_OK) == 0, "{}: not writable (for {})", dir.string(), for_output.string());
}

void refuseExisting(const std::filesystem::path& path, bool force) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(path, ec))) return;
  HATTR_THROW_UNLESS(force, "{}: already exists; add --force to replace it (nothing was written)", path.string());
}

}  // namespace

void checkOutputFiles(const std::vector<std::filesystem::path>& files, bool force) {
  for (const auto& file : files) {
    std::error_code ec;
    HATTR_THROW_UNLESS(!std::filesystem::is_directory(file, ec), "{}: expected a file name, got a folder", file.string());
    refuseExisting(file, force);
    checkWritableFolder(file.parent_path(), file, false);
  }
}

void checkOutputFolder(const std::filesystem::path& dir, const std::vector<std::string>& names, bool force) {
  for (const auto& name : names) refuseExisting(dir / name, force);
  checkWritableFolder(dir, dir, true);
}

namespace {

/// A recording that could not be written where asked: beside it under a new name, else in
/// the temporary folder. Returns where it went, if anywhere.
std::optional<std::filesystem::path> keepSomewhere(const HapticProfile& profile, const std::filesystem::path& file) {
  const std::string name = fmt::format("{}.rescued-{}.csv", file.filename().string(), ::getpid());
  std::error_code ec;
  const std::filesystem::path temp = std::filesystem::temp_directory_path(ec);  // may fail: TMPDIR not a folder
  for (const auto& folder : {file.parent_path(), ec ? std::filesystem::path("/tmp") : temp}) {
    try {
      io::writeProfileCsv(profile, folder / name, hattr::Overwrite::kRefuse);
      return folder / name;
    } catch (const std::exception&) {  // try the next place
    }
  }
  return std::nullopt;
}

}  // namespace

void writeRecording(const HapticProfile& profile, const std::filesystem::path& file, bool force) {
  try {
    io::writeProfileCsv(profile, file, force ? hattr::Overwrite::kReplace : hattr::Overwrite::kRefuse);
  } catch (const std::exception& e) {
    const std::string why = e.what();
    if (const auto kept = keepSomewhere(profile, file)) {
      throw Error(fmt::format("{}; the recording is kept in {}", why, kept->string()));
    }
    throw Error(fmt::format("{}; the recording could not be kept anywhere ({} samples lost)", why, profile.size()));
  }
}

// The progress line: drawn after a carriage return and an erase-line (ESC [K), cleared the same way.
Progress::Progress(std::string label, double total, std::string unit)
    : label_(std::move(label)), total_(total), unit_(std::move(unit)), shown_(onTerminal()) {}

Progress::~Progress() { finish(); }

bool Progress::onTerminal() {
  const char* term = std::getenv("TERM");
  return isatty(STDERR_FILENO) == 1 && !(term != nullptr && std::string_view(term) == "dumb");
}

void Progress::update(double done, const std::string& label) {
  if (!label.empty()) label_ = label;
  if (!shown_) return;
  // At most ten redraws a second; the end is always drawn.
  const auto now = std::chrono::steady_clock::now();
  if (drawn_ && now - last_draw_ < std::chrono::milliseconds(100) && done < total_) return;
  last_draw_ = now;
  if (total_ <= 0.0) {
    std::cerr << "\r\x1b[K" << label_ << std::flush;
    drawn_ = true;
    return;
  }
  // The bar, the count and an estimate of the time left from the rate so far.
  constexpr int kWidth = 30;
  const double fraction = std::clamp(done / total_, 0.0, 1.0);
  const int filled = static_cast<int>(fraction * kWidth);
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  std::string eta;
  const double left = fraction > 0.0 ? elapsed * (1.0 / fraction - 1.0) : 0.0;
  if (fraction < 1.0 && elapsed > 1.0 && left >= 1.0) eta = fmt::format(", about {:.0f} s left", left);
  const auto integral = [](double v) { return v == static_cast<double>(static_cast<long long>(v)); };
  const bool whole = integral(done) && integral(total_);
  const std::string count = whole ? fmt::format("{}/{}", static_cast<long long>(done), static_cast<long long>(total_))
                                  : fmt::format("{:.1f}/{:.1f}", done, total_);
  std::cerr << fmt::format("\r\x1b[K{} [{}{}] {} {}{}", label_, std::string(static_cast<std::size_t>(filled), '#'),
                           std::string(static_cast<std::size_t>(kWidth - filled), '.'), count, unit_, eta)
            << std::flush;
  drawn_ = true;
}

void Progress::stage(const std::string& label, double total) {
  label_ = label;
  total_ = total;
  start_ = std::chrono::steady_clock::now();
  drawn_ = false;  // drawn now, whatever the last redraw's time
  update(0.0);
}

void Progress::finish() {
  if (drawn_) std::cerr << "\r\x1b[K" << std::flush;
  drawn_ = false;
}

std::function<void(std::string_view, int, int)> stageProgress(Progress& progress, std::string prefix) {
  return [&progress, prefix = std::move(prefix)](std::string_view stage, int done, int total) {
    const std::string what = stage == "trials"    ? "running the study"
                             : stage == "scoring" ? "scoring recall trials"
                                                  : "writing the report";
    const std::string label = fmt::format("{}: {}", prefix, what);
    if (label != progress.label()) progress.stage(label, stage == "report" ? 0 : total);
    progress.update(done);
  };
}


std::string verdictsText(const servo::LoopJudgement& judgement) {
  std::string text;
  for (const auto& f : judgement.figures) {
    text += fmt::format("{}  {:<24} {:>10.4g} {:<3} ({})\n", servo::verdictName(f.verdict), f.name, f.value, f.unit, f.rule);
  }
  return text + fmt::format("verdict {}\n", servo::verdictName(judgement.overall));
}

std::vector<int> commaSeparatedInts(const std::string& text, std::string_view option) {
  std::vector<int> values;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    std::size_t used = 0;
    int n = 0;
    try {
      n = std::stoi(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    HATTR_THROW_UNLESS(used == item.size() && !item.empty(), "{}: expected comma-separated whole numbers, got \"{}\"",
                       option, item);
    values.push_back(n);
  }
  HATTR_THROW_UNLESS(!values.empty(), "{}: expected comma-separated whole numbers, got \"{}\"", option, text);
  return values;
}

std::pair<int, int> shardOf(const std::string& text, std::string_view option) {
  if (text.empty()) return {0, 1};
  int i = -1, n = 0;
  char slash = 0, extra = 0;
  std::istringstream in(text);
  const bool read = static_cast<bool>(in >> i >> slash >> n) && slash == '/' && !(in >> extra);
  HATTR_THROW_UNLESS(read && n >= 1 && i >= 0 && i < n, "{}: expected i/N with 0 <= i < N (e.g. 0/4), got \"{}\"",
                     option, text);
  return {i, n};
}

}  // namespace hattr::cli
