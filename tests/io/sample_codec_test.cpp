#include "hattr/io/sample_codec.hpp"

#include <bit>
#include <cstring>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <string>

#include <zstd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/core/error.hpp"
#include "support/test_support.hpp"

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
  for (const std::size_t n : {0u, 1u, 2u, 3u, 4u, 5u, 7u, 8u, 11u, 12u, 127u, 128u, 129u, 4500u}) {
    const auto samples = stroke(n, 1);
    const std::string blob = encodeSamples(samples, channels);
    EXPECT_TRUE(isEncodedSamples(blob));
    expectSameBits(decodeSamples(blob, channels, n), samples, channels);
  }
}

TEST(SampleCodec, LosslessKeepsSignedZerosSubnormalsAndExtremes) {
  const std::vector<Channel> channels = {Channel::kTime, Channel::kX, Channel::kVx, Channel::kFx, Channel::kCmdFx, Channel::kGuideFx};
  std::vector<Sample> samples(16);
  const double extremes[] = {-0.0, std::numeric_limits<double>::denorm_min(), 1e300, -1e300,
                             std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(), 1e-300, 0.0};
  for (std::size_t i = 0; i < samples.size(); ++i) {
    samples[i].t_s = static_cast<double>(i);
    samples[i].p_WT.x() = extremes[i % 8];
    samples[i].v_WT.x() = extremes[(i + 6) % 8];
    samples[i].f_user_W.x() = extremes[(i + 3) % 8];
    samples[i].f_guide_W.x() = extremes[(i + 5) % 8];
    samples[i].f_cmd_W.x() = extremes[(i + 1) % 8];
  }
  expectSameBits(decodeSamples(encodeSamples(samples, channels), channels, samples.size()), samples, channels);
}

/// Samples made with +, -, * and / of doubles and integer hashing only, so that they have the
/// same bits in every conforming build: the revision-1 blocks below were encoded from them.
double jitter(std::uint64_t i, std::uint64_t channel) {
  std::uint64_t h = (i + 1) * 0x9E3779B97F4A7C15ull ^ (channel + 1) * 0xC2B2AE3D27D4EB4Full;
  h ^= h >> 29;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 32;
  return static_cast<double>(static_cast<std::int64_t>(h % 2001) - 1000) * 1e-12;
}

std::vector<Sample> portableStroke(std::size_t n) {
  std::vector<Sample> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    Sample& s = out[i];
    const double t = static_cast<double>(i) / 1000.0;
    s.t_s = t;
    s.p_WT = Vec3(0.01 + 0.05 * t - 0.2 * t * t + jitter(i, 1), 0.02 - 0.03 * t + jitter(i, 2),
                  i % 16 < 8 ? 0.0 : 0.003 * t + jitter(i, 3));
    s.v_WT = Vec3(0.05 - 0.4 * t + jitter(i, 4) * 1e3, -0.03 + jitter(i, 5) * 1e3, jitter(i, 6));
    s.f_user_W = Vec3(0.1 * t + jitter(i, 7), -0.05 * t, i % 16 < 8 ? -1.0 + 2.0 * t + jitter(i, 9) : 0.0);
    s.f_guide_W = i % 20 < 10 ? Vec3(0.3 * t, -0.2 * t + jitter(i, 10), 0.0) : Vec3::Zero();
    s.f_cmd_W = s.f_guide_W - s.f_user_W;
    if (i % 7 == 0) s.f_cmd_W = 0.5 * s.f_cmd_W;
    s.in_contact = i % 16 < 8;
    s.pen_down = s.in_contact;
    s.pressure_raw = static_cast<double>(400 + i % 13);
    s.tilt_azimuth_rad = 0.8 + 0.01 * t;
    s.tilt_altitude_rad = 1.1;
  }
  return out;
}

std::string fromHex(std::string_view hex) {
  std::string bytes;
  for (std::size_t i = 0; i + 1 < hex.size(); i += 2) bytes.push_back(static_cast<char>(std::stoi(std::string(hex.substr(i, 2)), nullptr, 16)));
  return bytes;
}

/// portableStroke(40) on every stored channel, encoded by hattr 1e7c200 (revision 1, the
/// last build that wrote it): lossless, and at the default resolution.
constexpr std::string_view kRevision1Lossless =
    "4853430128000000150000000001000000000000000001020000000000000000020200000000000000000302000000000000000004020000"
    "000000000000050200000000000000000602000000000000000008020000000000000000090200000000000000000a020000000000000000"
    "0c0300000000000000000d0300000000000000000e0300000000000000000f02000000000000000010020000000000000000110200000000"
    "0000000012000000000000000000130000000000000000001400000000000000000015010000000000000000160100000000000000001e1b"
    "00000000000028b52ffd641e1a0553002a83fc1f38101869cf18e879e26f35cdf59d7a0233cafe8076bfb6562ec0fc51565da0c134c0ed21"
    "abde9faf4d5dd3408ec6280561430d47b8576e2953f4010b02f6014cfe4b735b65b824d76adcd7180c5caec0d099f17c0632900afa444571"
    "d3518b82304f4e8703a9db4c05bd76376ebbf6c5474be9d215cd1aa712760ba8490b749c5c6bd5c812960d3269c5e5d55bb398340d2e5f0c"
    "7030e8bd1b9945338ac46b02abc3d58948f84f6ad529618a4af74cb6494d8623ff5c3970f78de7f737f763c2fd170bb3fdc7c1f9fdcffeef"
    "8e8adfc10ddd564a2ac183ccf9522487a30fcf2b483760fe51256674fb82c6ef1314fcf1ff07ffc9f7fefcc60f84bf38fe7f3ffeff3fd691"
    "b2c4248aac9ad0ce240113a5647ba504bb06e936514529d9ca6accfdb9309eea12a2b9daa0ce811e9202b1839a49ba7027e966f7b2d81e82"
    "7e14cac11e76017d9510d1925f79464d452462ea9a0f7d3239c74ac07ae91a5d5588aa4dc44c7184fc5a526934f76929e03a00b6f6839374"
    "343563b7cd3095fd685c43b0aa5a31ebcdfab1593389505719c843f16cafde3af1f2558880789e84b0652a0a8b46eb92f0933a501cc3ec44"
    "ed0a79c142d454daa0198faeb8d215f17c977f904330ce5f3106a53a097bf33c0581acd52f0010cb5020db8dca519dfb339204467d14cba2"
    "808fccd1258eb827813c78e810357c51860f40005ec8c1f5c642cdf887954949c64388c49b1550692e89dfbb3f73cb208879981731eed2c2"
    "f25d4941390983f32ffef8fdf7ffbfccff0bdd565f590177464c994408f2f917c5b5e3e16dd36c89225e5cdd60ace711a797568fd9eb10f1"
    "d58fb0c8cc46229a1d581c2950dcedeafa2781cc9d5e9ac61f098268a2276d937be2b7b126ab5a7de3bc2ce2e5856a309561baf133ca61d2"
    "40a34fd6dd832bbd59d021bf4e7a2299e1a540437a1c319913a3c9b211604f8b1cc99efeb512c042f6920c55836356fac0fcd393aa16567b"
    "2275150d747dddd914a861dc3759be4795358e2837dd3504397d4bafffad465fa7a2598142287978f0c906671e4a855c6350286064f34c6a"
    "8228bab4979781cc8838c986c6de269814270d8bdd0a1d5047c338be0a1b54e86dea0ae2d5aa22ca4804f2d894d9e1ee004218799c305c86"
    "90ff85dc7b8f4413a004745748c32925d2c1d913892481e23b96806aa76b508bb16db6f39fc64dfbbff2b1fdffaff6df054ba320c3c0aa79"
    "8d03c64e407580e99a60235774c16b22a5859f38adaf68afe3d56a1d310424b3e0a85cd29e8134a4ab90d1090bfd846475ce260582ac03f2"
    "d83c54664559834c81550921e2135e1985aaa44164f07a704dc5400275b142cb0dca08b38b1a00c88b5b70d3400b6382a428409ac6096b49"
    "3ec354ac2048d4894e2dbc682c2dbd6a004af292dea648df0ed5815f246f188a850eed35b201d2988a3d29c929bd1930aaf4f252372484a6"
    "cbf918521b92dc926363a351a13d81d7b9455ac0df5c21daaeb05d7d787854ce10c5ec7ed8fdb037432f4d3ae440221c2d19c9260c08c0e4"
    "3613cc724ed61851d5ca9652a954b42e4895659f3b9f95b95a7b5d40756046657d23f8a6436940872ecc450f2c44ff37d97fffdff73f1b13"
    "fbf06dc9bd7f970205b3da9486133053d9a38bfc7f616959b902e8b3fc7a29a6e2f2472cddc091cd21d931f7ff19be77fcffefb911e6decb"
    "c32ffe370e9ba25905a215ff2f188c1bfea77656351bc0151bcdb1554aa9500e3ab9808593a065d7046b53c2d6bebc3ec6196f35494873c2"
    "8bb4195edba12867147a4d4747a290653e2ca9710c9db9701617d1cfe8dc63194f742c4463d7ad5281756310945918557f1deae0940578dc"
    "54d7b4779cb1fa71009bddfd2aa9dd9aec649ba001d47b402f0d0bc38ff95432ecc5dad2b6bc494131c887a74bc4f6236065795c16826e49"
    "d629ed16031133981bb3862f266a536a6d4b6f2d157161834122648f175602d878c5febb8889a08a7ec4626d6634b19c5712dd022932a32b"
    "177d6749dffc0a6fed06e502091b211c81d96e0d4601af342f0e708a2d4796398ad63e4455c5125911969335c804135657161eecbac19a2a"
    "027aaac8f86de4debf93d32e520ce9a909912317c486211fc3a6d716f500db5ae2a6a38928432189ffb29fa8ff9e4aa8ffff90dfbfa7ab9a"
    "18a05ea047110fd0d2d8cfc1f614e6d922980ad5092f9eeaa12c52b8a62e47433001ed37ae774a3068f4dfa1d16974fad39f3ea71f37f1e8"
    "3bf4dfdda1effa7fdbc4f7fedf7befffbdf7de4ba0cfe7f4d9ee1f7dfeefb1c4b5d5b5d5552c6ef932a39d7fb0c0d417f906c9c9906c75bc"
    "9c3e87dff99ddff99ddf7919a49fefe9f5f998a39e1f779e1ff7562bd0584d3758284e1eb60850cd153168ac44e7be84c4e22456b4987251"
    "0211e81e38dea3bad444f6d9fff54794499f8604f42e09c07c83009608fd89e23f193d468fd1e35e57fef19a9d4fff554fffff48607cb2fe"
    "cb3808fa87a210f4ffeff5bda7836a6cdb30718b2bb129e1f1ff87fee7b8f5e5583ddaf30512e691beb102038bc46cc9e478170afa75c5c4"
    "c69355fed3a2ccf38158806be7ff7de3f8e3388e7ff13bf0ffbeef7b8dcc8e03fbd9f25c20f5f57fdf77d00e586e6ee80f917bffae8744f3"
    "f7dff7fd3ead6a776469789e7fced2e27202c7bbb859f098e3234f47feffc1bef7fcc800326edd3855236488fa0915ed37fedfefdf9f87c1"
    "f8fd789ee38fe3378e83f33b1cfee6f9d70541cf4ccb5becbd23288786f39b637bd772041eac851ddc1c09480b9333ce083f203bc0496370"
    "77cdede467d59c0506943e28c858fd19724a39535b99257b11c964b9408681b9c9245611b1b26171104785db01e7b422a64b6a8180a861b9"
    "532522229a24750ac3015106a5ae444d0712e07071a82419e50c3284184344444644241019114961a131d25a20692110dad79d256c2ccfd0"
    "37b17accd4c8a1cfdfe544b5b53dc52a26658d98a8a54a51f647491166cd5953d41dcfa039d99ec79373ed7e16b4bef80a4270b7b286a088"
    "c0d6afc623758cdbb2ea624bcab216da97642e0b1a8681e1cd0b36c487a3ac9cda7212f18555281729afb744bd37600d38987fed42a05a9d"
    "05d0c12f41ae1c841e69d36829a9c8c243164262b6b16582962c40d215ea4fb1adc8c4901189d78d486f534d5577a1b83172408dc6cb3a3e"
    "3539c92c88ec4c07cc51d6283f68ad3f8f361b220d63f1d7b9545fcadc969d77098232a8cd1f2bbadadde82de518300d96e010e4d29d1640"
    "62b6b16582959c9ece3a5239261f1900f8c1c8a8b9e6ab8f50dc1a39a25ae3651d9f92919098ad61452a5c9d90033ee2f0ac212296c3121b"
    "bc2b59ca39601a2cc121c8a53b2d80c46c63cb042f399d16c509d97976cf47ebf87e0e008955b6a4a564442b9eee61ec93a4a21288a497e0"
    "b50257534ec2a6c112048a2c85d3024c0c31b64cd09213f8a68900c649735625d7b2d8571fa1386b99fb5a95788ebe6c17483816a95ed520"
    "e25e721678f38cb33d2e564aad40c43271abe3d168c68b680a4b21c0b74d02184fd694f321ccf05cba1094fa6953e2193db25d249158a48a"
    "5589087a8916c3beae935e7c48bf0cc7f828399ed87840c43271abe3d168c68b688a4be1a99396961218c61c8edb6915c2b64acbe1fca0ce"
    "523047b2f2517a8642b9d00ebe30dd997a14d1ec1f2cbb27d6ee816d7f6070110cce9146f77839d27d1ad518";
constexpr std::string_view kRevision1Quantized =
    "48534301280000001500010000018dedb5a0f7c6b03e01028dedb5a0f7c6b03e02028dedb5a0f7c6b03e03028dedb5a0f7c6b03e0402f168"
    "e388b5f8e43e0502f168e388b5f8e43e0602f168e388b5f8e43e0802fca9f1d24d62503f0902fca9f1d24d62503f0a02fca9f1d24d62503f"
    "0c03fca9f1d24d62503f0d03fca9f1d24d62503f0e03fca9f1d24d62503f0f02fca9f1d24d62503f1002fca9f1d24d62503f1102fca9f1d2"
    "4d62503f1200000000000000f03f1300000000000000f03f1400000000000000f03f15012d431cebe2361a3f16012d431cebe2361a3f1e1b"
    "00000000000028b52ffd641e1a6d0c00928d33364073d2012cfb0ebfd7f423feee5f62c3c83b77f42e70d905a2a4172bc64aaffdfff2533e"
    "089b08b857f699519376da6ebd1bd932c91416dbc2377a8eb6829e503c7b82c4c7c797f45814397dd973ef4e49091a8c982f18babfff3ec5"
    "f68bed1ae3a83ff7efbc6b1ba572b207abc32608242c192a27a34ebfe7b07dca5a3e60440a4a522e170c29078888abaf1aa519134883079b"
    "9c0353836a727a404e0bc8e90052f61104584c149215181334ad959e833ed776c3b30a616db4eef6d74d15b383b2d219515badd95e50134a"
    "2270a8514576a6a05cd80e3083294a3a12c0c0911e4522460c12488c0416080512cc4c1965566b06c78396907dce43deb1379b37da83e95c"
    "fd4d4d978255b990f2d1a2da57d241e5eb3840f6a75a614b2a94c111c9225d8f0a4410ea5cc68ae226d77a96db30fa22feb253133ef850fe"
    "72f72763df078287fe0830c90cfe0c99d0ab6f9928cd431e36549ca97bb73e5e444ea9f0341d8274600ba7a998d7c4dc7e65162619cc5eb5"
    "8682ac2b272e9354885395fd148385c182a6ed5105cb9c7050";

TEST(SampleCodec, Revision1BlocksAreStillReadBitForBit) {
  const auto channels = everyStoredChannel();
  const auto samples = portableStroke(40);
  const std::string lossless = fromHex(kRevision1Lossless);
  ASSERT_EQ(sampleEncodingOf(lossless), "hsc1");
  expectSameBits(decodeSamples(lossless, channels, samples.size()), samples, channels);

  const std::string quantized = fromHex(kRevision1Quantized);
  const auto read = decodeSamples(quantized, channels, samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    for (const Channel c : channels) {
      const double step = defaultResolution().at(c);
      ASSERT_EQ(channelValue(read[i], c), static_cast<double>(std::llround(channelValue(samples[i], c) / step)) * step)
          << "sample " << i << " channel " << channelInfo(c).name;
    }
  }
  // What this build writes is the second revision, and it reads back the same.
  const std::string again = encodeSamples(samples, channels);
  EXPECT_EQ(sampleEncodingOf(again), kSampleEncoding);
  expectSameBits(decodeSamples(again, channels, samples.size()), samples, channels);
}

/// Bytes per sample that `column` adds to a block of time and velocity.
double bytesPerSampleOf(Channel column, const std::vector<Sample>& samples) {
  const std::vector<Channel> base = {Channel::kTime, Channel::kVx};
  std::vector<Channel> with = base;
  with.push_back(column);
  const std::string a = encodeSamples(samples, base), b = encodeSamples(samples, with);
  expectSameBits(decodeSamples(b, with, samples.size()), samples, with);
  return (static_cast<double>(b.size()) - static_cast<double>(a.size())) / static_cast<double>(samples.size());
}

TEST(SampleCodec, APositionThatStepsWithItsVelocityCostsAFractionOfOneThatDoesNot) {
  // A device that integrates its velocity (p_i = p_(i-1) + Δt·v_i) and one whose position is
  // its own: same sizes of motion, each with noise in every digit of the velocity.
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 1e-4);
  std::vector<Sample> stepped(3000), own(3000);
  for (std::size_t i = 0; i < stepped.size(); ++i) {
    const double t = static_cast<double>(i) * 1e-3;
    for (auto* s : {&stepped[i], &own[i]}) {
      s->t_s = t;
      s->v_WT.x() = 0.05 * std::sin(4.0 * t) + noise(rng);
    }
    stepped[i].p_WT.x() = i == 0 ? 0.01 : stepped[i - 1].p_WT.x() + (t - stepped[i - 1].t_s) * stepped[i].v_WT.x();
    own[i].p_WT.x() = 0.01 + 0.0125 * (1.0 - std::cos(4.0 * t)) + noise(rng) * 1e-3;
  }
  const double with_velocity = bytesPerSampleOf(Channel::kX, stepped);
  const double without = bytesPerSampleOf(Channel::kX, own);
  EXPECT_LT(with_velocity, 1.5);  // the rounding of one addition
  EXPECT_GT(without, 4.0);
}

TEST(SampleCodec, AMissThatRepeatsEveryFourSamplesCostsAFractionOfOneThatDoesNot) {
  // A smooth velocity with a ripple that repeats every 4 samples (a sensor read at a quarter
  // of the rate and interpolated, say), against the same ripple drawn afresh each time.
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> ripple(-1e-5, 1e-5);
  const double pattern[4] = {ripple(rng), ripple(rng), ripple(rng), ripple(rng)};
  std::vector<Sample> periodic(3000), fresh(3000);
  for (std::size_t i = 0; i < periodic.size(); ++i) {
    const double t = static_cast<double>(i) * 1e-3;
    periodic[i].t_s = fresh[i].t_s = t;
    periodic[i].v_WT.y() = 0.02 + 0.01 * t + pattern[i % 4];
    fresh[i].v_WT.y() = 0.02 + 0.01 * t + ripple(rng);
  }
  const double repeating = bytesPerSampleOf(Channel::kVy, periodic);
  const double not_repeating = bytesPerSampleOf(Channel::kVy, fresh);
  EXPECT_LT(repeating, 0.5 * not_repeating);
}

/// The frame's content of an encoded block whose header (up to its content size) takes
/// `header_bytes`.
std::string contentOf(const std::string& blob, std::size_t header_bytes) {
  const std::string_view frame = std::string_view(blob).substr(header_bytes + 8);
  std::string content(ZSTD_getFrameContentSize(frame.data(), frame.size()), '\0');
  EXPECT_EQ(ZSTD_decompress(content.data(), content.size(), frame.data(), frame.size()), content.size());
  return content;
}

/// The prediction each block of one chosen column took, past the first block (whose start
/// lacks the history every prediction needs).
std::set<int> choicesAfterTheFirstBlock(const std::string& content, std::size_t at, std::size_t blocks) {
  std::set<int> taken;
  for (std::size_t b = 1; b < blocks; ++b) taken.insert(static_cast<unsigned char>(content[at + b]));
  return taken;
}

TEST(SampleCodec, EachPredictionIsChosenWhereItFitsAndReadBack) {
  // One column of 1 024 samples (8 blocks) per case, each made for one prediction to leave the
  // fewest bits: 3 a cubic (its miss changes slowly), 5 the quadratic plus its miss 8 samples
  // before (a ripple of period 8), 7 the kinematic prediction plus its miss 4 samples before (a
  // position that steps with its velocity, with a ripple of period 4 on top).
  const std::size_t n = 1024, blocks = n / 128;
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> ripple(-1e-6, 1e-6);
  std::normal_distribution<double> noise(0.0, 1e-4);
  double period8[8], period4[4];
  for (double& r : period8) r = ripple(rng);
  for (double& r : period4) r = ripple(rng);
  std::vector<Sample> quartic(n), rippled(n), stepping(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * 1e-3;
    for (auto* s : {&quartic[i], &rippled[i], &stepping[i]}) s->t_s = t;
    quartic[i].v_WT.x() = 0.01 + 2.0 * t * t * t * t;
    rippled[i].v_WT.x() = 0.02 + 0.01 * t + period8[i % 8];
    stepping[i].v_WT.x() = 0.05 * std::sin(4.0 * t) + noise(rng);
    stepping[i].p_WT.x() = i == 0 ? 0.01 : stepping[i - 1].p_WT.x() + 1e-3 * stepping[i].v_WT.x();
  }
  for (std::size_t i = 0; i < n; ++i) stepping[i].p_WT.x() += period4[i % 4];

  const std::vector<Channel> velocity = {Channel::kTime, Channel::kVx};
  for (const auto& [samples, wanted] : {std::pair{&quartic, 3}, std::pair{&rippled, 5}}) {
    const std::string blob = encodeSamples(*samples, velocity);
    expectSameBits(decodeSamples(blob, velocity, n), *samples, velocity);
    const std::size_t header = 12 + 2 * 11;  // vx's choices open the content after the header
    EXPECT_EQ(choicesAfterTheFirstBlock(contentOf(blob, header), header, blocks), std::set<int>{wanted});
  }
  const std::vector<Channel> position = {Channel::kTime, Channel::kX, Channel::kVx};
  const std::string blob = encodeSamples(stepping, position);
  expectSameBits(decodeSamples(blob, position, n), stepping, position);
  const std::size_t header = 12 + 3 * 11 + 16;  // with x's a and b
  EXPECT_EQ(choicesAfterTheFirstBlock(contentOf(blob, header), header, blocks), std::set<int>{7});
}

TEST(SampleCodec, AnySetOfChannelsWithAnyValuesRoundTrips) {
  // Random channel sets (a position without its velocity, a commanded force without its parts,
  // no time...) and random columns: smooth with noise, constant, steps, awkward floats; some
  // long enough for many blocks, some shorter than a prediction's history.
  const std::uint64_t seed = test::testSeed(14);
  SCOPED_TRACE(::testing::Message() << "HATTR_TEST_SEED=" << seed);
  std::mt19937_64 rng(seed);
  const auto all = everyStoredChannel();
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int round = 0; round < 40; ++round) {
    std::vector<Channel> channels;
    for (const Channel c : all) {
      if (rng() % 2 == 0) channels.push_back(c);
    }
    if (channels.empty()) channels.push_back(all[rng() % all.size()]);
    const std::size_t n = rng() % 4 == 0 ? rng() % 16 : rng() % 700;
    std::vector<Sample> samples(n);
    for (const Channel c : channels) {
      const auto kind = rng() % 4;
      const double scale = std::pow(10.0, static_cast<double>(rng() % 12) - 8.0);
      for (std::size_t i = 0; i < n; ++i) {
        const double t = static_cast<double>(i) * 1e-3;
        double v = 0.0;
        if (kind == 0) v = scale * (std::sin(7.0 * t + static_cast<double>(round)) + 1e-6 * unit(rng));
        if (kind == 1) v = scale;
        if (kind == 2) v = i % 97 < 40 ? 0.0 : scale * std::round(4.0 * unit(rng));
        if (kind == 3) v = test::randomProfile(rng, 1, RawChannels{true, true}).samples()[0].p_WT.x();
        if (c == Channel::kContact || c == Channel::kPenDown) v = v > 0.0 ? 1.0 : 0.0;
        setChannelValue(samples[i], c, v);
      }
    }
    SCOPED_TRACE(::testing::Message() << "round " << round << ", " << n << " samples, " << channels.size() << " channels");
    expectSameBits(decodeSamples(encodeSamples(samples, channels), channels, n), samples, channels);
  }
}

/// `blob` with its frame's content changed by `change` and compressed again (with a new
/// checksum): what a writer with a bug would store.
template <class Change>
std::string withContent(const std::string& blob, std::size_t header_bytes, Change change) {
  const std::string_view frame = std::string_view(blob).substr(header_bytes + 8);
  std::string content(ZSTD_getFrameContentSize(frame.data(), frame.size()), '\0');
  EXPECT_EQ(ZSTD_decompress(content.data(), content.size(), frame.data(), frame.size()), content.size());
  change(content);
  ZSTD_CCtx* cctx = ZSTD_createCCtx();
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 1);
  std::string out(ZSTD_compressBound(content.size()), '\0');
  out.resize(ZSTD_compress2(cctx, out.data(), out.size(), content.data(), content.size()));
  ZSTD_freeCCtx(cctx);
  std::string changed = blob.substr(0, header_bytes);
  const std::uint64_t size = content.size();
  changed.append(reinterpret_cast<const char*>(&size), 8);
  return changed + out;
}

TEST(SampleCodec, ARevision2BlockWithImpossibleContentIsRefusedWithWhatIsWrong) {
  // Time and x, with x's velocity: x chooses among 8 predictions in each of 2 blocks, and is
  // kept as bit lengths and bits. The header: 12 bytes, 3 channels of 11, x's a and b (16).
  const std::vector<Channel> channels = {Channel::kTime, Channel::kX, Channel::kVx};
  const auto samples = stroke(200, 8);
  const std::string blob = encodeSamples(samples, channels);
  const std::size_t header = 12 + 3 * 11 + 16;
  const std::size_t choices = header;  // x's 2 choices, then vx's 2
  const auto message = [&](const std::string& bytes) {
    try {
      (void)decodeSamples(bytes, channels, samples.size());
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("decoded");
  };
  ASSERT_EQ(message(withContent(blob, header, [](std::string&) {})), "decoded");
  EXPECT_THAT(message(withContent(blob, header, [&](std::string& c) { c[choices + 1] = 8; })),
              HasSubstr("channel x, block 1: prediction 8, expected below 8 (damaged)"));
  EXPECT_THAT(message(withContent(blob, header, [&](std::string& c) { c[choices + 2] = 6; })),
              HasSubstr("channel vx, block 0: prediction 6, expected below 6 (damaged)"));
  // The lengths follow the choices and time's byte planes; x's are first.
  const std::size_t lengths = choices + 4 + 200 * 8;
  EXPECT_THAT(message(withContent(blob, header, [&](std::string& c) { c[lengths + 3] = 70; })),
              HasSubstr("channel x, sample 3: a residual of"));
  EXPECT_THAT(message(withContent(blob, header, [](std::string& c) { c.pop_back(); })), HasSubstr("bytes of bits"));
  EXPECT_THAT(message(withContent(blob, header, [](std::string& c) { c.push_back('\0'); })), HasSubstr("bytes of bits"));
  // The content's declared size must fit its parts.
  std::string oversized = blob;
  const std::uint64_t huge = std::uint64_t{1} << 40;
  std::memcpy(oversized.data() + header, &huge, sizeof huge);
  EXPECT_THAT(message(oversized), HasSubstr("says 1099511627776 bytes of header and residuals, expected"));
  // The kinematic coefficients must be finite.
  std::string infinite = blob;
  const double inf = std::numeric_limits<double>::infinity();
  std::memcpy(infinite.data() + 12 + 3 * 11, &inf, sizeof inf);
  EXPECT_THAT(message(infinite), HasSubstr("channel x: kinematic coefficients inf and"));
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
  predictor[12 + 11 * 1 + 1] = 1;  // x's chosen predictions said to be a line
  EXPECT_THAT(message(predictor, channels, 500), HasSubstr("channel x: predictor 1, expected 5"));
  std::string coding = blob;
  coding[12 + 11 * 1 + 2] = 0;  // x's bit lengths said to be byte planes
  EXPECT_THAT(message(coding, channels, 500), HasSubstr("channel x: layout 0, expected 1"));
  std::string reserved = blob;
  reserved[11] = 7;
  EXPECT_THAT(message(reserved, channels, 500), HasSubstr("flags are 0x00 0x07"));
}

TEST(SampleCodec, AQuantizedStepChangedOutsideTheChecksumIsRefused) {
  const auto channels = everyStoredChannel();
  const auto samples = stroke(300, 6);
  std::string blob = encodeSamples(samples, channels, defaultResolution());
  const double coarser = 2e-6;  // x's step, 1 µm, made 2 µm
  std::memcpy(blob.data() + 12 + 11 * 1 + 3, &coarser, sizeof coarser);
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
