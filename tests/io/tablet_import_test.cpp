#include "hattr/io/tablet_import.hpp"

#include <cmath>
#include <numbers>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "hattr/analysis/kinematics.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/units.hpp"

namespace hattr::io {
namespace {

using ::testing::HasSubstr;

HapticProfile svc(const std::string& text) {
  std::istringstream in(text);
  return importSvc2004(in, "U0S0.TXT", svc2004Calibration());
}

std::string svcError(const std::string& text) {
  try {
    (void)svc(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

HapticProfile susig(const std::string& text) {
  std::istringstream in(text);
  return importSusig(in, "sig.txt", susigCalibration());
}

std::string susigError(const std::string& text) {
  try {
    (void)susig(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// ---- SVC2004 ---------------------------------------------------------------------------

TEST(Svc2004Import, ConvertsTabletUnitsToSi) {
  const HapticProfile p = svc("3\n100 200 5000 0 900 900 1023\n200 200 5010 1 900 900 0\n300 100 5020 1 0 450 511\n");
  ASSERT_EQ(p.size(), 3u);
  EXPECT_DOUBLE_EQ(p[0].t_s, 0.0);
  EXPECT_DOUBLE_EQ(p[2].t_s, 0.020);
  // Placed on the paper: the pen-down box (x 100..300, y 100..200 units) centred on the origin.
  EXPECT_DOUBLE_EQ(p[0].p_WT.x(), (100 - 200) * 1e-5);
  EXPECT_DOUBLE_EQ(p[2].p_WT.y(), (100 - 150) * 1e-5);  // SVC2004's y grows away from the writer
  EXPECT_EQ(p.metadata().extra.at("placed_shift_m"), "-0.002 -0.0015");
  EXPECT_DOUBLE_EQ(p[0].tilt_altitude_rad, std::numbers::pi / 2);
  EXPECT_DOUBLE_EQ(p[0].pressure_raw, 1023.0);
  // Vertical pen at full scale: the whole calibrated force presses the paper down, and by
  // default that is what the default pen renders continuously.
  EXPECT_NEAR(p[0].f_user_W.z(), -1.75, 1e-12);
  EXPECT_NEAR(p[0].f_user_W.head<2>().norm(), 0.0, 1e-12);
  EXPECT_EQ(p.metadata().nominal_rate_hz, 100.0);
  EXPECT_EQ(p.metadata().extra.at("time_origin_s"), "5");
}

TEST(Svc2004Import, TabletCoordinatesAreKeptWhenTheCalibrationSaysSo) {
  TabletCalibration cal = svc2004Calibration();
  cal.centre_on_paper = false;
  std::istringstream in("2\n100 200 5000 1 900 900 10\n300 100 5010 1 900 900 10\n");
  const HapticProfile p = importSvc2004(in, "U0S0.TXT", cal);
  EXPECT_DOUBLE_EQ(p[0].p_WT.x(), 100 * 1e-5);
  EXPECT_DOUBLE_EQ(p[1].p_WT.y(), 100 * 1e-5);
  EXPECT_EQ(p.metadata().extra.count("placed_shift_m"), 0u);
  EXPECT_FALSE(parseCalibration(R"({"centre_on_paper": false})", "cal.json", svc2004Calibration()).centre_on_paper);
}

TEST(Svc2004Import, PenDownFollowsPressureOrButtonAndPenUpPointsAreKept) {
  const HapticProfile p = svc("3\n0 0 0 0 900 900 10\n0 0 10 1 900 900 0\n0 0 20 0 900 900 0\n");
  ASSERT_EQ(p.size(), 3u);
  EXPECT_TRUE(p[0].pen_down);   // pressure > 0 although button is 0
  EXPECT_TRUE(p[1].pen_down);   // button bit 0 set
  EXPECT_FALSE(p[2].pen_down);  // neither: a pen-up point, kept
  EXPECT_EQ(p[2].f_user_W, Vec3::Zero());
}

TEST(Svc2004Import, ALiftIsAGapBeforeAButtonZeroPointAndBecomesOnePenUpSample) {
  // Two strokes: the second starts 100 ms after the first ends, with button 0 and pressure; a
  // dropped point inside it (20 ms, button 1) is no lift.
  const HapticProfile p = svc("6\n0 0 0 0 900 900 10\n100 0 10 1 900 900 20\n200 0 20 1 900 900 30\n"
                              "900 500 120 0 900 900 40\n1000 500 130 1 900 900 50\n1200 500 150 1 900 900 60\n");
  ASSERT_EQ(p.size(), 7u);
  EXPECT_EQ(p.metadata().extra.at("inserted_lift_samples"), "1");
  EXPECT_EQ(p.metadata().nominal_rate_hz, 100.0);  // from the file's own steps, not the mark's
  const Sample& up = p[3];
  EXPECT_FALSE(up.pen_down);
  EXPECT_FALSE(up.in_contact);
  EXPECT_DOUBLE_EQ(up.t_s, 0.030);
  EXPECT_EQ(up.p_WT, p[2].p_WT);
  EXPECT_EQ(up.f_user_W, Vec3::Zero());
  EXPECT_EQ(up.v_WT, Vec3::Zero());
  EXPECT_EQ(up.pressure_raw, 0.0);
  EXPECT_TRUE(p[4].pen_down);
  // Velocities are differenced within each stroke: the first stroke's end one-sided (1 mm in
  // 10 ms), the second's start too, never across the lift.
  EXPECT_NEAR(p[2].v_WT.x(), 0.1, 1e-12);
  EXPECT_NEAR(p[4].v_WT.x(), 0.1, 1e-12);
  const analysis::TrialKinematics k = analysis::trialKinematics(p);
  EXPECT_EQ(k.strokes, 2u);
  EXPECT_EQ(k.pen_lifts, 1u);
  EXPECT_NEAR(k.in_air_time_s, 0.100, 1e-12);
  EXPECT_NEAR(k.writing_time_s, 0.050, 1e-12);
}

TEST(Svc2004Import, APointAlreadyUpNeedsNoMark) {
  // The tablet reported the pen in the air (button 0, no pressure): the stroke ends there.
  const HapticProfile p = svc("3\n0 0 0 1 900 900 10\n0 0 50 0 900 900 0\n0 0 100 0 900 900 10\n");
  EXPECT_EQ(p.size(), 3u);
  EXPECT_EQ(p.metadata().extra.at("inserted_lift_samples"), "0");
}

TEST(Svc2004Import, TiltSplitsTheAxialForceAsThePaperSays) {
  // Altitude 30°, azimuth 90° (barrel toward +x): normal part F·sin θ, tangential F·cos θ toward −x.
  const HapticProfile p = svc("1\n0 0 0 1 900 300 1023\n");
  const double f = svc2004Calibration().pressure_max_N;
  EXPECT_NEAR(p[0].f_user_W.z(), -f * std::sin(units::degreesToRadians(30)), 1e-12);
  EXPECT_NEAR(p[0].f_user_W.x(), -f * std::cos(units::degreesToRadians(30)), 1e-12);
  EXPECT_NEAR(p[0].f_user_W.y(), 0.0, 1e-12);
}

TEST(Svc2004Import, RetimesRepeatedAndBackwardStampsWithoutDroppingPoints) {
  const HapticProfile p = svc("6\n0 0 100 1 0 900 5\n0 0 110 1 0 900 5\n0 0 110 1 0 900 5\n"
                              "0 0 101 1 0 900 5\n0 0 140 1 0 900 5\n0 0 150 1 0 900 5\n");
  ASSERT_EQ(p.size(), 6u);
  EXPECT_DOUBLE_EQ(p[2].t_s, 0.020);  // 110 and 101 spread evenly between 110 and 140
  EXPECT_DOUBLE_EQ(p[3].t_s, 0.030);
  EXPECT_DOUBLE_EQ(p.duration_s(), 0.050);
  EXPECT_EQ(p.metadata().extra.at("retimed_samples"), "2");
}

TEST(Svc2004Import, RetimesARepeatedLastStampByOneUnit) {
  const HapticProfile p = svc("3\n0 0 100 1 0 900 5\n0 0 110 1 0 900 5\n0 0 110 1 0 900 5\n");
  EXPECT_DOUBLE_EQ(p[2].t_s, 0.011);
}

TEST(Svc2004ImportErrors, NameTheLineAndTheField) {
  EXPECT_EQ(svcError(""), "U0S0.TXT: empty file: expected the number of points on line 1");
  EXPECT_EQ(svcError("many\n"), "U0S0.TXT:1: expected the number of points (an integer > 0), got \"many\"");
  EXPECT_EQ(svcError("2\n1 2 3 1 0 900 5\n1 2 4 1 0 900\n"),
            "U0S0.TXT:3: expected 7 fields (X Y T button azimuth altitude pressure), got 6");
  EXPECT_EQ(svcError("1\n1 2 x 1 0 900 5\n"), "U0S0.TXT:2: field T: expected a number, got \"x\"");
  EXPECT_EQ(svcError("3\n1 2 3 1 0 900 5\n"), "U0S0.TXT: line 1 announces 3 points, the file has 1");
}

// ---- SUSIG ----------------------------------------------------------------------------

TEST(SusigImport, ReadsHeaderDataSizeAndStrokeEnds) {
  const HapticProfile p = susig(
      "X, Y, TStamp, Pres., EndPts\nDataSize: 4\n"
      "100, 200, 0, 128, 0\n110, 205, 10, 255, 1\n300, 200, 50, 64, 0\n310, 210, 60, 0, 1\n");
  // The first stroke's end is followed by a lift the tablet did not report: one pen-up sample,
  // one period (10 ms, the median step) after it, where the pen left.
  ASSERT_EQ(p.size(), 5u);
  EXPECT_FALSE(p[2].pen_down);
  EXPECT_DOUBLE_EQ(p[2].t_s, 0.020);
  EXPECT_EQ(p[2].p_WT, p[1].p_WT);
  EXPECT_EQ(p.metadata().extra.at("inserted_lift_samples"), "1");
  EXPECT_DOUBLE_EQ(p[3].t_s, 0.050);
  EXPECT_NEAR(p[1].f_user_W.z(), -susigCalibration().pressure_max_N, 1e-12);
  EXPECT_FALSE(p[4].pen_down);
  EXPECT_FALSE(p.hasChannel(Channel::kAzimuth));
  EXPECT_TRUE(p.hasChannel(Channel::kPressure));
  EXPECT_EQ(p.metadata().extra.at("strokes"), "2");
}

TEST(SusigImport, AcceptsDataSizeFirstAndBlankSeparators) {
  const HapticProfile p = susig("DataSize: 2\nX Y TStamp Pres. EndPts\n1 2 0 5 0\n3 4 10 5 1\n");
  EXPECT_EQ(p.size(), 2u);
}

TEST(SusigImportErrors, NameTheLineAndTheField) {
  EXPECT_EQ(susigError("X, Y, Time, Pres., EndPts\n"),
            "sig.txt:1: expected the header \"X, Y, TStamp, Pres., EndPts\", got \"X, Y, Time, Pres., EndPts\"");
  EXPECT_EQ(susigError("1, 2, 3, 4, 0\n"), "sig.txt:1: data before the header and DataSize lines");
  EXPECT_EQ(susigError("DataSize: 2\nX, Y, TStamp, Pres., EndPts\n1, 2, 0, 5, 0\n"),
            "sig.txt: DataSize announces 2 points, the file has 1");
  EXPECT_EQ(susigError("DataSize: 1\nX, Y, TStamp, Pres., EndPts\n1, 2, 0, 5, 3\n"),
            "sig.txt:3: field EndPts: expected 0 or 1, got \"3\"");
  EXPECT_EQ(susigError("DataSize: 1\nX, Y, TStamp, Pres., EndPts\n1, 2, 0, p, 0\n"),
            "sig.txt:3: field Pres.: expected a number, got \"p\"");
}

// ---- Calibration -------------------------------------------------------------------------

TEST(TabletCalibration, JsonOverridesOnlyTheKeysItNames) {
  const TabletCalibration cal =
      parseCalibration(R"({"pressure_max_N": 3.5, "y_axis_toward_writer": true})", "cal.json", svc2004Calibration());
  EXPECT_EQ(cal.pressure_max_N, 3.5);
  EXPECT_TRUE(cal.y_axis_toward_writer);
  EXPECT_EQ(cal.metres_per_unit_x, svc2004Calibration().metres_per_unit_x);
}

TEST(TabletCalibration, BadJsonNamesKeyRangeAndValue) {
  const auto error = [](const std::string& json) {
    try {
      (void)parseCalibration(json, "cal.json", svc2004Calibration());
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(error(R"({"pressure_max_N": -1})"), "cal.json: key pressure_max_N: expected a number in [0.001, 1000], got -1");
  EXPECT_THAT(error(R"({"presure_max_N": 2})"), HasSubstr("cal.json: unknown key \"presure_max_N\": expected one of"));
  EXPECT_EQ(error(R"({"pressure_exponent": "2"})"),
            "cal.json: key pressure_exponent: expected a number in [0.1, 10], got \"2\"");
  EXPECT_THAT(error("{"), HasSubstr("cal.json: not valid JSON"));
  EXPECT_EQ(error("[1]"), "cal.json: expected a JSON object, got array");
}

TEST(TabletCalibration, PressureCurveIsMonotoneAndClamped) {
  TabletCalibration cal = svc2004Calibration();
  cal.pressure_exponent = 1.5;
  EXPECT_EQ(pressureToNewtons(0, cal), 0.0);
  EXPECT_DOUBLE_EQ(pressureToNewtons(1023, cal), cal.pressure_max_N);
  EXPECT_DOUBLE_EQ(pressureToNewtons(5000, cal), cal.pressure_max_N);
  EXPECT_LT(pressureToNewtons(300, cal), pressureToNewtons(301, cal));
}

}  // namespace
}  // namespace hattr::io
