#pragma once
// What the study tests share: a short expert reference.

#include <filesystem>

#include "hattr/io/profile_csv.hpp"

namespace hattr::session {

/// A short expert profile (0.3 s, pressing 1.2 N, skill "dash") written to `file`.
inline void writeExpert(const std::filesystem::path& file) {
  HapticProfile p({.subject = "expert", .skill = "dash", .nominal_rate_hz = 100.0});
  for (int i = 0; i <= 30; ++i) {
    Sample s;
    s.t_s = i * 0.01;
    s.p_WT = Vec3(0.001 * i, 0.0, 0.0);
    s.v_WT = Vec3(0.1, 0.0, 0.0);
    s.f_user_W = Vec3(0.0, 0.0, -1.2);
    s.pen_down = true;
    p.append(s);
  }
  io::writeProfileCsv(p, file, hattr::Overwrite::kReplace);
}

/// SQL that turns a study file of this build back into schema 4's tables (what migration 4 -> 5
/// added goes away; it only added columns), before a test sets an older user_version.
inline constexpr const char* kBackToSchema4 =
    "ALTER TABLE trials DROP COLUMN skill; ALTER TABLE trials DROP COLUMN schedule_session; "
    "ALTER TABLE trials DROP COLUMN day; ALTER TABLE trials DROP COLUMN block; "
    "ALTER TABLE subjects DROP COLUMN group_name; ";

}  // namespace hattr::session
