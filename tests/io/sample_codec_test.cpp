#include "hattr/io/sample_codec.hpp"

#include <bit>
#include <cstring>
#include <cmath>
#include <limits>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"

namespace hattr::io {
namespace {

using ::testing::HasSubstr;

/// The stored channels of a profile with tilt and pressure, in file-column order.
std::vector<Channel> everyStoredChannel() {
  std::vector<Channel> channels;
  for (const auto& info : allChannels()) {
    if (!info.derived) channels.push_back(info.channel);
  }
  return channels;
}

/// A smooth pen stroke with noise in the last digits, guidance on and off, the commanded
/// force as the safety path makes it (guidance minus the user's force, now and then not).
std::vector<Sample> stroke(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1e-9);
  std::vector<Sample> samples(n);
  for (std::size_t i = 0; i < n; ++i) {
    Sample& s = samples[i];
    const double t = static_cast<double>(i) * 1e-3;
    s.t_s = t;
    s.p_WT = Vec3(0.02 * std::sin(3.0 * t) + noise(rng), 0.01 * std::cos(2.0 * t) + noise(rng), 0.0005 + noise(rng));
    s.v_WT = Vec3(0.06 * std::cos(3.0 * t), -0.02 * std::sin(2.0 * t), noise(rng));
    s.f_user_W = Vec3(0.1 * std::sin(t), 0.05 * std::cos(t), -1.0 + 0.2 * std::sin(5.0 * t));
    s.f_guide_W = i % 700 < 350 ? Vec3(0.3 * std::sin(t), 0.0, 0.01) : Vec3::Zero();
    s.f_cmd_W = s.f_guide_W - s.f_user_W;
    if (i % 97 == 0) s.f_cmd_W *= 0.5;  // the rate limit had its say
    s.in_contact = i % 500 > 20;
    s.pen_down = s.in_contact;
    s.pressure_raw = std::round(400.0 + 100.0 * std::sin(t));
    s.tilt_azimuth_rad = 0.8 + 0.01 * std::sin(t);
    s.tilt_altitude_rad = 1.1;
  }
  return samples;
}

/// Every double of every sample, bit for bit.
void expectSameBits(const std::vector<Sample>& got, const std::vector<Sample>& want, std::span<const Channel> channels) {
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    for (const Channel c : channels) {
      ASSERT_EQ(std::bit_cast<std::uint64_t>(channelValue(got[i], c)), std::bit_cast<std::uint64_t>(channelValue(want[i], c)))
          << "sample " << i << " channel " << channelInfo(c).name;
    }
  }
}

TEST(SampleCodec, LosslessGivesBackEveryDoubleBitForBit) {
  const auto channels = everyStoredChannel();
  for (const std::size_t n : {0u, 1u, 2u, 3u, 4u, 4500u}) {
    const auto samples = stroke(n, 1);
    const std::string blob = encodeSamples(samples, channels);
    EXPECT_TRUE(isEncodedSamples(blob));
    expectSameBits(decodeSamples(blob, channels, n), samples, channels);
  }
}

TEST(SampleCodec, LosslessKeepsSignedZerosSubnormalsAndExtremes) {
  const std::vector<Channel> channels = {Channel::kTime, Channel::kX, Channel::kFx, Channel::kCmdFx, Channel::kGuideFx};
  std::vector<Sample> samples(8);
  const double extremes[] = {-0.0, std::numeric_limits<double>::denorm_min(), 1e300, -1e300,
                             std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(), 1e-300, 0.0};
  for (std::size_t i = 0; i < samples.size(); ++i) {
    samples[i].t_s = static_cast<double>(i);
    samples[i].p_WT.x() = extremes[i];
    samples[i].f_user_W.x() = extremes[(i + 3) % 8];
    samples[i].f_guide_W.x() = extremes[(i + 5) % 8];
    samples[i].f_cmd_W.x() = extremes[(i + 1) % 8];
  }
  expectSameBits(decodeSamples(encodeSamples(samples, channels), channels, samples.size()), samples, channels);
}

TEST(SampleCodec, ASmoothStrokeTakesLessThanAThirdOfItsRawBytes) {
  // Prediction, byte planes and zstd together: the constant and predictable channels cost
  // almost nothing (the study store's real figures are in docs/BENCHMARKS.md).
  const auto channels = everyStoredChannel();
  const auto samples = stroke(4500, 2);
  const std::string blob = encodeSamples(samples, channels);
  EXPECT_LT(blob.size(), samples.size() * channels.size() * 8 / 3);
}

TEST(SampleCodec, ADeclaredResolutionStoresWholeStepsAndReadsBackExactlyThem) {
  const auto channels = everyStoredChannel();
  const auto samples = stroke(3000, 3);
  const ChannelResolution& steps = defaultResolution();
  const std::string blob = encodeSamples(samples, channels, steps);
  const auto read = decodeSamples(blob, channels, samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    for (const Channel c : channels) {
      const double step = steps.at(c);
      const auto k = static_cast<double>(std::llround(channelValue(samples[i], c) / step));
      ASSERT_EQ(channelValue(read[i], c), k * step) << "sample " << i << " channel " << channelInfo(c).name;
    }
  }
  // What was read is stored again as the same blob: nothing drifts.
  EXPECT_EQ(encodeSamples(read, channels, steps), blob);
  // And it is much smaller than the lossless one.
  EXPECT_LT(blob.size() * 3, encodeSamples(samples, channels).size());
}

TEST(SampleCodec, AValueBeyondTheResolutionsRangeIsRefusedNamingTheChannel) {
  const std::vector<Channel> channels = {Channel::kTime, Channel::kX};
  std::vector<Sample> samples(2);
  samples[1].p_WT.x() = 1e12;  // 1e18 micrometres
  try {
    (void)encodeSamples(samples, channels, defaultResolution());
    FAIL() << "encoded";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("channel x, sample 1: 1000000000000 m is beyond 2^51 steps of 1e-06 m"));
  }
  ChannelResolution missing = {{Channel::kTime, 1e-6}};
  EXPECT_THROW((void)encodeSamples(samples, channels, missing), InputError);
}

TEST(SampleCodec, ADamagedOrForeignBlockIsRefusedWithWhatIsWrong) {
  const auto channels = everyStoredChannel();
  const auto samples = stroke(500, 4);
  const std::string blob = encodeSamples(samples, channels);
  const auto message = [&](std::string_view bytes, std::span<const Channel> on, std::size_t count) {
    try {
      (void)decodeSamples(bytes, on, count);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("decoded");
  };
  EXPECT_THAT(message("raw doubles", channels, 500), HasSubstr("expected an encoded block"));
  EXPECT_THAT(message(blob, channels, 499), HasSubstr("holds 500 samples, expected 499"));
  const std::vector<Channel> fewer(channels.begin(), channels.end() - 1);
  EXPECT_THAT(message(blob, fewer, 500), HasSubstr("holds 21 channels, expected 20"));
  std::vector<Channel> swapped = channels;
  std::swap(swapped[1], swapped[2]);
  EXPECT_THAT(message(blob, swapped, 500), HasSubstr("encoded channel 1 is number 1, expected 2 (y)"));
  EXPECT_THAT(message(blob.substr(0, blob.size() - 10), channels, 500), HasSubstr("compressed residuals"));
  std::string flipped = blob;
  flipped[flipped.size() - 20] = static_cast<char>(flipped[flipped.size() - 20] ^ 0x5A);
  EXPECT_NE(message(flipped, channels, 500), "decoded");
  EXPECT_THAT(message(blob + "x", channels, 500), HasSubstr("not exactly one zstd frame"));
  // The header outside the frame is checked against its copy under the checksum.
  std::string predictor = blob;
  predictor[12 + 10 * 1 + 1] = 1;  // x's quadratic said to be a line
  EXPECT_THAT(message(predictor, channels, 500), HasSubstr("channel x: predictor 1, expected 2"));
  std::string reserved = blob;
  reserved[11] = 7;
  EXPECT_THAT(message(reserved, channels, 500), HasSubstr("flags are 0x00 0x07"));
}

TEST(SampleCodec, AQuantizedStepChangedOutsideTheChecksumIsRefused) {
  const auto channels = everyStoredChannel();
  const auto samples = stroke(300, 6);
  std::string blob = encodeSamples(samples, channels, defaultResolution());
  const double coarser = 2e-6;  // x's step, 1 µm, made 2 µm
  std::memcpy(blob.data() + 12 + 10 * 1 + 2, &coarser, sizeof coarser);
  try {
    (void)decodeSamples(blob, channels, samples.size());
    FAIL() << "decoded";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("header is damaged"));
  }
}

TEST(SampleCodec, ACommandedForceWithItsOwnStepIsPredictedAsTheOthers) {
  // Steps that differ from its parts' leave the commanded force to the quadratic, both ways.
  const auto channels = everyStoredChannel();
  const auto samples = stroke(800, 7);
  ChannelResolution steps = defaultResolution();
  steps[Channel::kCmdFx] = 1e-4;
  const std::string blob = encodeSamples(samples, channels, steps);
  const auto read = decodeSamples(blob, channels, samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    ASSERT_EQ(read[i].f_cmd_W.x(), static_cast<double>(std::llround(samples[i].f_cmd_W.x() / 1e-4)) * 1e-4) << i;
    ASSERT_EQ(read[i].f_cmd_W.y(), static_cast<double>(std::llround(samples[i].f_cmd_W.y() / 1e-3)) * 1e-3) << i;
  }
  EXPECT_EQ(encodeSamples(read, channels, steps), blob);
}

TEST(SampleCodec, ResolutionsReadFromJsonAndSayWhatIsWrong) {
  EXPECT_TRUE(parseResolution("\"lossless\"", "study.json: storage.resolution").empty());
  EXPECT_EQ(parseResolution("\"default\"", "r"), defaultResolution());
  const ChannelResolution mixed = parseResolution(R"({"x": 1e-7, "fz": 0.0001})", "r");
  EXPECT_EQ(mixed.at(Channel::kX), 1e-7);
  EXPECT_EQ(mixed.at(Channel::kFz), 1e-4);
  EXPECT_EQ(mixed.at(Channel::kY), 1e-6);  // the default's
  EXPECT_EQ(parseResolution(resolutionJson(mixed), "r"), mixed);
  EXPECT_EQ(resolutionJson({}), "\"lossless\"");
  const auto message = [](std::string_view json) {
    try {
      (void)parseResolution(json, "study.json: storage.resolution");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("parsed");
  };
  EXPECT_THAT(message(R"({"speed": 1})"), HasSubstr("study.json: storage.resolution: \"speed\": expected a stored channel"));
  EXPECT_THAT(message(R"({"x": 0})"), HasSubstr("\"x\": expected a step > 0 in m, got 0"));
  EXPECT_THAT(message(R"("fine")"), HasSubstr("expected \"lossless\", \"default\" or an object of channel steps"));
  EXPECT_THAT(message("{"), HasSubstr("expected \"lossless\""));
}

}  // namespace
}  // namespace hattr::io
