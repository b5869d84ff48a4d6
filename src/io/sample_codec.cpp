// The compact sample encoding (include/hattr/io/sample_codec.hpp). Compiled with
// -ffp-contract=off (src/CMakeLists.txt): the predictions must round the same in every build.

#include "hattr/io/sample_codec.hpp"

#include <zstd.h>

#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <nlohmann/json.hpp>

#include "hattr/core/error.hpp"

namespace hattr::io {
namespace {

static_assert(std::endian::native == std::endian::little, "the sample encoding is little-endian");
static_assert(FLT_EVAL_METHOD == 0, "the predictions must round to double at every step (no x87 extended precision)");

constexpr char kMagic[4] = {'H', 'S', 'C', '\x01'};  // hattr sample columns, version 1
constexpr std::size_t kHeaderBytes = 12;             // magic, u32 count, u16 channels, u8 flags, u8 0
constexpr std::size_t kChannelBytes = 10;            // u8 channel, u8 predictor, f64 step
constexpr std::uint8_t kQuantized = 1;
constexpr double kLargestSteps = 2251799813685248.0;  // 2^51: below it llround(k·step / step) is k again

/// How a channel's value is predicted from what was decoded before it.
enum class Predictor : std::uint8_t {
  kPrevious = 0,   ///< the last value (flags, raw pressure)
  kLine = 1,       ///< through the last two (time, tilt)
  kQuadratic = 2,  ///< through the last three (positions, velocities, forces)
  kCommand = 3,    ///< the commanded force: guidance force minus the user's force, same axis
};

/// The user's and the guidance force channel of a commanded-force channel's axis.
std::pair<Channel, Channel> commandParts(Channel cmd) {
  switch (cmd) {
    case Channel::kCmdFx: return {Channel::kFx, Channel::kGuideFx};
    case Channel::kCmdFy: return {Channel::kFy, Channel::kGuideFy};
    default: return {Channel::kFz, Channel::kGuideFz};
  }
}

bool isCommand(Channel c) { return c == Channel::kCmdFx || c == Channel::kCmdFy || c == Channel::kCmdFz; }

/// The predictor of each channel (the commanded force needs its axis's other two channels).
Predictor predictorOf(Channel c, std::span<const Channel> channels) {
  if (isCommand(c)) {
    const auto [user, guide] = commandParts(c);
    const bool both = std::find(channels.begin(), channels.end(), user) != channels.end() &&
                      std::find(channels.begin(), channels.end(), guide) != channels.end();
    return both ? Predictor::kCommand : Predictor::kQuadratic;
  }
  switch (c) {
    case Channel::kContact:
    case Channel::kPenDown:
    case Channel::kPressure: return Predictor::kPrevious;
    case Channel::kTime:
    case Channel::kAzimuth:
    case Channel::kAltitude: return Predictor::kLine;
    default: return Predictor::kQuadratic;
  }
}

// ---- Predictions: doubles (lossless) and whole steps (declared resolution) ----------------

std::uint64_t zigzag(std::uint64_t difference) { return (difference << 1) ^ (0 - (difference >> 63)); }
std::uint64_t unzigzag(std::uint64_t z) { return (z >> 1) ^ (0 - (z & 1)); }

/// A non-finite prediction (from values near the largest double) becomes 0, so that every
/// platform predicts the same bits (NaNs' bits differ between them).
double finiteOrZero(double value) { return std::isfinite(value) ? value : 0.0; }

/// Lossless columns: predicted in IEEE doubles, differenced as 64-bit patterns.
struct Doubles {
  using Value = double;
  static std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v); }
  static double fromBits(std::uint64_t b) { return std::bit_cast<double>(b); }
  static double line(double a, double b) { return finiteOrZero(2.0 * a - b); }
  static double quadratic(double a, double b, double c) { return finiteOrZero(3.0 * a - 3.0 * b + c); }
  static double command(double guide, double user) { return finiteOrZero(guide - user); }
};

/// Columns of whole steps: predicted and differenced in wrapping 64-bit integers.
struct Steps {
  using Value = std::uint64_t;
  static std::uint64_t bits(std::uint64_t v) { return v; }
  static std::uint64_t fromBits(std::uint64_t b) { return b; }
  static std::uint64_t line(std::uint64_t a, std::uint64_t b) { return 2 * a - b; }
  static std::uint64_t quadratic(std::uint64_t a, std::uint64_t b, std::uint64_t c) { return 3 * (a - b) + c; }
  static std::uint64_t command(std::uint64_t guide, std::uint64_t user) { return guide - user; }
};

/// The prediction of value `i` of a column from the values before it (fewer at its start).
template <class D>
typename D::Value predict(Predictor p, const typename D::Value* column, std::size_t i) {
  if (i == 0) return 0;
  if (p == Predictor::kPrevious || i == 1) return column[i - 1];
  if (p == Predictor::kLine || i == 2) return D::line(column[i - 1], column[i - 2]);
  return D::quadratic(column[i - 1], column[i - 2], column[i - 3]);
}

/// A column's residuals: the zigzagged differences from the predictions. `guide` and `user`
/// are the axis's columns for kCommand.
template <class D>
void encodeColumn(Predictor p, const typename D::Value* column, const typename D::Value* guide,
                  const typename D::Value* user, std::uint64_t* out, std::size_t n) {
  const auto residual = [](typename D::Value value, typename D::Value predicted) {
    return zigzag(D::bits(value) - D::bits(predicted));
  };
  if (p == Predictor::kCommand) {
    for (std::size_t i = 0; i < n; ++i) out[i] = residual(column[i], D::command(guide[i], user[i]));
    return;
  }
  const std::size_t head = std::min<std::size_t>(n, 3);
  for (std::size_t i = 0; i < head; ++i) out[i] = residual(column[i], predict<D>(p, column, i));
  // Past the first three, one predictor without branches.
  if (p == Predictor::kPrevious) {
    for (std::size_t i = head; i < n; ++i) out[i] = residual(column[i], column[i - 1]);
  } else if (p == Predictor::kLine) {
    for (std::size_t i = head; i < n; ++i) out[i] = residual(column[i], D::line(column[i - 1], column[i - 2]));
  } else {
    for (std::size_t i = head; i < n; ++i) {
      out[i] = residual(column[i], D::quadratic(column[i - 1], column[i - 2], column[i - 3]));
    }
  }
}

/// The column back from its residuals, value by value (each prediction needs the values
/// before it).
template <class D>
void decodeColumn(Predictor p, const std::uint64_t* residuals, const typename D::Value* guide,
                  const typename D::Value* user, typename D::Value* column, std::size_t n) {
  const auto value = [](std::uint64_t r, typename D::Value predicted) { return D::fromBits(unzigzag(r) + D::bits(predicted)); };
  if (p == Predictor::kCommand) {
    for (std::size_t i = 0; i < n; ++i) column[i] = value(residuals[i], D::command(guide[i], user[i]));
    return;
  }
  const std::size_t head = std::min<std::size_t>(n, 3);
  for (std::size_t i = 0; i < head; ++i) column[i] = value(residuals[i], predict<D>(p, column, i));
  if (p == Predictor::kPrevious) {
    for (std::size_t i = head; i < n; ++i) column[i] = value(residuals[i], column[i - 1]);
  } else if (p == Predictor::kLine) {
    for (std::size_t i = head; i < n; ++i) column[i] = value(residuals[i], D::line(column[i - 1], column[i - 2]));
  } else {
    for (std::size_t i = head; i < n; ++i) {
      column[i] = value(residuals[i], D::quadratic(column[i - 1], column[i - 2], column[i - 3]));
    }
  }
}

/// Byte planes: byte b of every word, for b = 0..7 (smooth data leaves long runs in the
/// high planes).
std::string shuffled(const std::uint64_t* words, std::size_t n) {
  std::string out(n * 8, '\0');
  for (std::size_t w = 0; w < n; ++w) {
    for (std::size_t b = 0; b < 8; ++b) out[b * n + w] = static_cast<char>(words[w] >> (8 * b));
  }
  return out;
}

void unshuffle(std::string_view planes, std::uint64_t* words) {
  const std::size_t n = planes.size() / 8;
  const auto* bytes = reinterpret_cast<const unsigned char*>(planes.data());
  for (std::size_t w = 0; w < n; ++w) {
    std::uint64_t word = 0;
    for (std::size_t b = 0; b < 8; ++b) word |= static_cast<std::uint64_t>(bytes[b * n + w]) << (8 * b);
    words[w] = word;
  }
}

template <class T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

template <class T>
T get(std::string_view blob, std::size_t at) {
  T value;
  std::memcpy(&value, blob.data() + at, sizeof(T));
  return value;
}

std::string_view nameOf(Channel c) { return channelInfo(c).name; }

/// zstd's contexts, one of each per thread, kept for the thread's life.
ZSTD_CCtx* compressionContext() {
  thread_local const std::unique_ptr<ZSTD_CCtx, decltype(&ZSTD_freeCCtx)> context(ZSTD_createCCtx(), &ZSTD_freeCCtx);
  HATTR_THROW_UNLESS(context != nullptr, "sample encoding: zstd: out of memory");
  return context.get();
}

ZSTD_DCtx* decompressionContext() {
  thread_local const std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> context(ZSTD_createDCtx(), &ZSTD_freeDCtx);
  HATTR_THROW_UNLESS(context != nullptr, "samples: zstd: out of memory");
  return context.get();
}

/// One whole zstd frame (RFC 8878) that declares `content_size` bytes, with its content's
/// checksum, and small enough to hold them: checked before anything is allocated.
void checkFrame(std::string_view frame, std::uint64_t content_size) {
  HATTR_THROW_UNLESS(ZSTD_getFrameContentSize(frame.data(), frame.size()) == content_size,
                     "samples: the compressed residuals are not one zstd frame of {} bytes", content_size);
  const std::size_t whole = ZSTD_findFrameCompressedSize(frame.data(), frame.size());
  HATTR_THROW_UNLESS(!ZSTD_isError(whole) && whole == frame.size(),
                     "samples: the compressed residuals are not exactly one zstd frame ({} bytes stored)", frame.size());
  // The frame header descriptor follows the 4-byte magic number; bit 2 says a checksum ends it.
  HATTR_THROW_UNLESS(frame.size() > 4 && (static_cast<unsigned char>(frame[4]) & 0x04) != 0,
                     "samples: the compressed residuals carry no checksum");
  // A zstd block of at most 128 KiB takes at least 4 bytes (an RLE block): no more content fits.
  HATTR_THROW_UNLESS(content_size <= (frame.size() / 4 + 1) * 131072,
                     "samples: {} bytes of compressed residuals cannot hold {} bytes", frame.size(), content_size);
}

/// The columns in the order they can be decoded: every commanded force after its parts.
std::vector<std::size_t> decodingOrder(std::span<const Predictor> predictors) {
  std::vector<std::size_t> order;
  for (std::size_t c = 0; c < predictors.size(); ++c) {
    if (predictors[c] != Predictor::kCommand) order.push_back(c);
  }
  for (std::size_t c = 0; c < predictors.size(); ++c) {
    if (predictors[c] == Predictor::kCommand) order.push_back(c);
  }
  return order;
}

std::size_t columnOf(std::span<const Channel> channels, Channel c) {
  return static_cast<std::size_t>(std::find(channels.begin(), channels.end(), c) - channels.begin());
}

/// In whole steps the commanded force is predicted from its parts only where all three share
/// the step (else their difference is not in its steps): a quadratic otherwise.
Predictor stepPredictor(Predictor p, std::span<const Channel> channels, std::span<const double> steps, std::size_t c) {
  if (p != Predictor::kCommand) return p;
  const auto [user, guide] = commandParts(channels[c]);
  const bool same = steps[c] == steps[columnOf(channels, user)] && steps[c] == steps[columnOf(channels, guide)];
  return same ? Predictor::kCommand : Predictor::kQuadratic;
}

}  // namespace

const ChannelResolution& defaultResolution() {
  static const ChannelResolution resolution = [] {
    ChannelResolution r;
    r[Channel::kTime] = 1e-6;
    for (Channel c : {Channel::kX, Channel::kY, Channel::kZ}) r[c] = 1e-6;
    for (Channel c : {Channel::kVx, Channel::kVy, Channel::kVz}) r[c] = 1e-5;
    for (Channel c : {Channel::kFx, Channel::kFy, Channel::kFz, Channel::kCmdFx, Channel::kCmdFy, Channel::kCmdFz,
                      Channel::kGuideFx, Channel::kGuideFy, Channel::kGuideFz}) {
      r[c] = 1e-3;
    }
    for (Channel c : {Channel::kContact, Channel::kPenDown, Channel::kPressure}) r[c] = 1.0;
    for (Channel c : {Channel::kAzimuth, Channel::kAltitude}) r[c] = 1e-4;
    return r;
  }();
  return resolution;
}

ChannelResolution parseResolution(std::string_view json_text, std::string_view where) {
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(json_text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(fmt::format("{}: expected \"lossless\", \"default\" or an object of channel steps, got {} ({})",
                                 where, json_text, e.what()));
  }
  if (json.is_string() && json.get<std::string>() == "lossless") return {};
  if (json.is_string() && json.get<std::string>() == "default") return defaultResolution();
  HATTR_THROW_UNLESS(json.is_object(), "{}: expected \"lossless\", \"default\" or an object of channel steps, got {}",
                     where, json.dump());
  // Named channels take their step; the others keep the default's.
  ChannelResolution resolution = defaultResolution();
  for (const auto& [name, step] : json.items()) {
    const auto channel = channelFromName(name);
    HATTR_THROW_UNLESS(channel && !channelInfo(*channel).derived,
                       "{}: \"{}\": expected a stored channel (t, x, y, z, vx, vy, vz, fx, fy, fz, cmd_fx, cmd_fy, "
                       "cmd_fz, guide_fx, guide_fy, guide_fz, contact, pen_down, pressure, azimuth, altitude)",
                       where, name);
    HATTR_THROW_UNLESS(step.is_number() && std::isfinite(step.get<double>()) && step.get<double>() > 0.0,
                       "{}: \"{}\": expected a step > 0 in {}, got {}", where, name, channelInfo(*channel).unit,
                       step.dump());
    resolution[*channel] = step.get<double>();
  }
  return resolution;
}

std::string resolutionJson(const ChannelResolution& resolution) {
  if (resolution.empty()) return "\"lossless\"";
  nlohmann::json json = nlohmann::json::object();
  for (const auto& [channel, step] : resolution) json[std::string(nameOf(channel))] = step;
  return json.dump();
}

bool isEncodedSamples(std::string_view blob) noexcept {
  return blob.size() >= sizeof kMagic && std::memcmp(blob.data(), kMagic, sizeof kMagic) == 0;
}

std::string encodeSamples(std::span<const Sample> samples, std::span<const Channel> channels,
                          const ChannelResolution& resolution, int level) {
  const std::size_t n = samples.size();
  const std::size_t m = channels.size();
  HATTR_THROW_UNLESS(n <= 0xFFFFFFFFu && m >= 1 && m <= 0xFFFF, "sample encoding: {} samples on {} channels", n, m);
  HATTR_THROW_UNLESS(level >= 1 && level <= 19, "sample encoding: zstd level: expected 1 to 19, got {}", level);
  const bool quantized = !resolution.empty();

  // The header: what the blob holds, and how each channel was predicted.
  std::vector<Predictor> predictors;
  std::vector<double> steps;
  std::string blob(kMagic, sizeof kMagic);
  put<std::uint32_t>(blob, static_cast<std::uint32_t>(n));
  put<std::uint16_t>(blob, static_cast<std::uint16_t>(m));
  put<std::uint8_t>(blob, quantized ? kQuantized : 0);
  put<std::uint8_t>(blob, 0);
  for (const Channel c : channels) {
    predictors.push_back(predictorOf(c, channels));
    double step = 0.0;
    if (quantized) {
      const auto it = resolution.find(c);
      HATTR_THROW_UNLESS(it != resolution.end() && std::isfinite(it->second) && it->second > 0.0,
                         "sample encoding: the declared resolution has no step > 0 for channel {}", nameOf(c));
      step = it->second;
    }
    steps.push_back(step);
    put<std::uint8_t>(blob, static_cast<std::uint8_t>(c));
    put<std::uint8_t>(blob, static_cast<std::uint8_t>(predictors.back()));
    put<double>(blob, step);
  }

  // Each column as doubles (lossless) or whole steps, then its residuals against the
  // predictions, zigzagged, column after column.
  const auto values = std::make_unique_for_overwrite<double[]>(n * m);
  for (std::size_t c = 0; c < m; ++c) {
    for (std::size_t i = 0; i < n; ++i) values[c * n + i] = channelValue(samples[i], channels[c]);
  }
  const auto words = std::make_unique_for_overwrite<std::uint64_t[]>(n * m);
  if (!quantized) {
    for (std::size_t c = 0; c < m; ++c) {
      const auto [user, guide] = commandParts(channels[c]);
      const bool command = predictors[c] == Predictor::kCommand;
      encodeColumn<Doubles>(predictors[c], values.get() + c * n, command ? values.get() + columnOf(channels, guide) * n : nullptr,
                            command ? values.get() + columnOf(channels, user) * n : nullptr, words.get() + c * n, n);
    }
  } else {
    const auto k = std::make_unique_for_overwrite<std::uint64_t[]>(n * m);
    for (std::size_t c = 0; c < m; ++c) {
      for (std::size_t i = 0; i < n; ++i) {
        const double v = values[c * n + i] / steps[c];
        HATTR_THROW_UNLESS(std::isfinite(values[c * n + i]), "sample encoding: channel {}, sample {}: not a number: {}",
                           nameOf(channels[c]), i, values[c * n + i]);
        HATTR_THROW_UNLESS(std::abs(v) <= kLargestSteps,
                           "sample encoding: channel {}, sample {}: {} {} is beyond 2^51 steps of {} {}", nameOf(channels[c]),
                           i, values[c * n + i], channelInfo(channels[c]).unit, steps[c], channelInfo(channels[c]).unit);
        k[c * n + i] = static_cast<std::uint64_t>(std::llround(v));
      }
    }
    for (std::size_t c = 0; c < m; ++c) {
      const auto [user, guide] = commandParts(channels[c]);
      const Predictor p = stepPredictor(predictors[c], channels, steps, c);
      const bool command = p == Predictor::kCommand;
      encodeColumn<Steps>(p, k.get() + c * n, command ? k.get() + columnOf(channels, guide) * n : nullptr,
                          command ? k.get() + columnOf(channels, user) * n : nullptr, words.get() + c * n, n);
    }
  }

  // The header again, then the byte planes, compressed: zstd's checksum covers both.
  const std::string planes = blob + shuffled(words.get(), n * m);
  put<std::uint64_t>(blob, planes.size());
  const std::size_t at = blob.size();
  blob.resize(at + ZSTD_compressBound(planes.size()));
  // With zstd's checksum of the content: a damaged block is refused, never read as samples.
  // The thread keeps its context (and its tables) from one trial to the next.
  ZSTD_CCtx* context = compressionContext();
  ZSTD_CCtx_reset(context, ZSTD_reset_session_and_parameters);
  ZSTD_CCtx_setParameter(context, ZSTD_c_compressionLevel, level);
  ZSTD_CCtx_setParameter(context, ZSTD_c_checksumFlag, 1);
  const std::size_t written = ZSTD_compress2(context, blob.data() + at, blob.size() - at, planes.data(), planes.size());
  HATTR_THROW_UNLESS(!ZSTD_isError(written), "sample encoding: zstd: {}", ZSTD_getErrorName(written));
  blob.resize(at + written);
  return blob;
}

std::vector<Sample> decodeSamples(std::string_view blob, std::span<const Channel> channels, std::size_t count) {
  // The header, checked against what the store says the blob holds.
  HATTR_THROW_UNLESS(isEncodedSamples(blob) && blob.size() >= kHeaderBytes,
                     "samples: expected an encoded block (starting \"HSC\\x01\", at least {} bytes), got {} bytes",
                     kHeaderBytes, blob.size());
  const std::size_t n = get<std::uint32_t>(blob, 4);
  const std::size_t m = get<std::uint16_t>(blob, 8);
  const auto flags = get<std::uint8_t>(blob, 10);
  const bool quantized = (flags & kQuantized) != 0;
  HATTR_THROW_UNLESS((flags & ~kQuantized) == 0 && get<std::uint8_t>(blob, 11) == 0,
                     "samples: the encoded block's flags are {:#04x} {:#04x}, expected 0x00 or 0x01, then 0x00", flags,
                     get<std::uint8_t>(blob, 11));
  HATTR_THROW_UNLESS(n == count, "samples: the encoded block holds {} samples, expected {}", n, count);
  HATTR_THROW_UNLESS(m == channels.size(), "samples: the encoded block holds {} channels, expected {}", m,
                     channels.size());
  HATTR_THROW_UNLESS(blob.size() >= kHeaderBytes + m * kChannelBytes + 8,
                     "samples: the encoded block is cut short in its header ({} bytes)", blob.size());
  std::vector<Predictor> predictors(m);
  std::vector<double> steps(m);
  for (std::size_t c = 0; c < m; ++c) {
    const std::size_t at = kHeaderBytes + c * kChannelBytes;
    const auto channel = get<std::uint8_t>(blob, at);
    const auto predictor = get<std::uint8_t>(blob, at + 1);
    steps[c] = get<double>(blob, at + 2);
    HATTR_THROW_UNLESS(channel == static_cast<std::uint8_t>(channels[c]),
                       "samples: encoded channel {} is number {}, expected {} ({})", c, channel,
                       static_cast<int>(channels[c]), nameOf(channels[c]));
    const Predictor expected = predictorOf(channels[c], channels);
    HATTR_THROW_UNLESS(predictor == static_cast<std::uint8_t>(expected), "samples: channel {}: predictor {}, expected {}",
                       nameOf(channels[c]), predictor, static_cast<int>(expected));
    HATTR_THROW_UNLESS(quantized ? std::isfinite(steps[c]) && steps[c] > 0.0 : steps[c] == 0.0,
                       "samples: channel {}: step {} in a {} block", nameOf(channels[c]), steps[c],
                       quantized ? "quantized" : "lossless");
    predictors[c] = static_cast<Predictor>(predictor);
  }

  // The frame: the header's copy and the byte planes, under zstd's checksum.
  const std::size_t payload_at = kHeaderBytes + m * kChannelBytes;
  const std::uint64_t content_size = get<std::uint64_t>(blob, payload_at);
  HATTR_THROW_UNLESS(content_size == payload_at + n * m * 8,
                     "samples: the encoded block says {} bytes of header and residuals, expected {}", content_size,
                     payload_at + n * m * 8);
  const std::string_view frame = blob.substr(payload_at + 8);
  checkFrame(frame, content_size);
  const auto content = std::make_unique_for_overwrite<char[]>(content_size);
  const std::size_t got = ZSTD_decompressDCtx(decompressionContext(), content.get(), content_size, frame.data(), frame.size());
  HATTR_THROW_UNLESS(!ZSTD_isError(got) && got == content_size, "samples: the compressed residuals are damaged: {}",
                     ZSTD_isError(got) ? ZSTD_getErrorName(got) : "short");
  HATTR_THROW_UNLESS(std::memcmp(content.get(), blob.data(), payload_at) == 0,
                     "samples: the encoded block's header is damaged (it differs from its checksummed copy)");
  const auto words = std::make_unique_for_overwrite<std::uint64_t[]>(n * m);
  unshuffle(std::string_view(content.get() + payload_at, n * m * 8), words.get());

  // Each column from its residuals and predictions, the commanded forces after their parts.
  const auto values = std::make_unique_for_overwrite<double[]>(n * m);
  if (!quantized) {
    for (const std::size_t c : decodingOrder(predictors)) {
      const auto [user, guide] = commandParts(channels[c]);
      const bool command = predictors[c] == Predictor::kCommand;
      decodeColumn<Doubles>(predictors[c], words.get() + c * n, command ? values.get() + columnOf(channels, guide) * n : nullptr,
                            command ? values.get() + columnOf(channels, user) * n : nullptr, values.get() + c * n, n);
    }
  } else {
    const auto k = std::make_unique_for_overwrite<std::uint64_t[]>(n * m);
    for (const std::size_t c : decodingOrder(predictors)) {
      const auto [user, guide] = commandParts(channels[c]);
      const Predictor p = stepPredictor(predictors[c], channels, steps, c);
      const bool command = p == Predictor::kCommand;
      decodeColumn<Steps>(p, words.get() + c * n, command ? k.get() + columnOf(channels, guide) * n : nullptr,
                          command ? k.get() + columnOf(channels, user) * n : nullptr, k.get() + c * n, n);
      for (std::size_t i = 0; i < n; ++i) {
        values[c * n + i] = static_cast<double>(static_cast<std::int64_t>(k[c * n + i])) * steps[c];
      }
    }
  }

  // Back into samples; every value must be finite, as a profile's are.
  std::vector<Sample> samples(n);
  for (std::size_t c = 0; c < m; ++c) {
    for (std::size_t i = 0; i < n; ++i) {
      const double v = values[c * n + i];
      HATTR_THROW_UNLESS(std::isfinite(v), "samples: channel {}, sample {}: decoded a non-finite value",
                         nameOf(channels[c]), i);
      setChannelValue(samples[i], channels[c], v);
    }
  }
  return samples;
}

}  // namespace hattr::io
