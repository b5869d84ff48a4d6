#pragma once
/// When each subject's sessions are due (docs/studies.md "Sessions on other days"): session k
/// falls on the local calendar date of the subject's first session plus day_k − day_0 days.
/// A session already begun goes on at any time; the first session may begin at any time.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hattr/session/study_database.hpp"

namespace hattr::session {

/// A calendar date in the station's local time zone.
struct LocalDate {
  int year = 1970;
  int month = 1;  ///< 1 to 12
  int day = 1;    ///< 1 to 31
  [[nodiscard]] std::string iso() const;  ///< "2026-11-27"
  friend auto operator<=>(const LocalDate&, const LocalDate&) = default;
};

/// Today's local date.
LocalDate localToday();
/// The local date of a UTC time as the study database stores it ("2026-11-27T02:40:00Z");
/// InputError for anything else.
LocalDate localDateOfUtc(std::string_view utc_iso8601);
/// `date` moved by `days` (negative: back).
LocalDate addDays(const LocalDate& date, int days);
/// Days from `from` to `to` (negative when `to` is earlier).
int daysBetween(const LocalDate& from, const LocalDate& to);

/// Where a subject stands in the schedule.
struct SubjectSchedule {
  enum class Timing {
    kDone,        ///< every trial completed
    kInProgress,  ///< the session of the next trial has begun: it goes on
    kAnyTime,     ///< the first session, not begun
    kDue,         ///< the next session is due today
    kEarly,       ///< due later (days_off days from today)
    kOverdue,     ///< was due days_off days ago
  };
  Timing timing = Timing::kAnyTime;
  int session = -1;                ///< the next trial's session, from 0 (-1: done)
  int sessions = 0;                ///< sessions in the schedule
  int day = 0;                     ///< the next trial's session's day offset
  std::optional<LocalDate> due;    ///< the next session's date (none for kAnyTime, kDone)
  int days_off = 0;                ///< kEarly: days until due; kOverdue: days since
  /// Whether the next trial may run on `today`: anything but kEarly and kDone.
  [[nodiscard]] bool runnable() const noexcept { return timing != Timing::kDone && timing != Timing::kEarly; }
};
std::string_view timingName(SubjectSchedule::Timing timing);  ///< "done", "in-progress", "any-time", ...

/// The subject's place in the schedule on `today`, from its trials (StudyDatabase::trials).
SubjectSchedule subjectSchedule(const StudyDefinition& study, const std::vector<TrialRecord>& trials,
                                const LocalDate& today);

/// One line for a person: "next session 2 of 3 (day 1): due today", "... early: due on
/// 2026-11-28 (in 1 day)", "... overdue since 2026-11-26 (1 day)", "session 1 of 3 in
/// progress", "done".
std::string scheduleText(const SubjectSchedule& schedule);

}  // namespace hattr::session
