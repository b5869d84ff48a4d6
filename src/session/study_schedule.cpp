#include "hattr/session/study_schedule.hpp"

#include <algorithm>
#include <charconv>
#include <ctime>

#include <fmt/format.h>

#include "hattr/core/error.hpp"

namespace hattr::session {
namespace {

/// Days since 1970-01-01 of a proleptic Gregorian date (Howard Hinnant's days_from_civil).
std::int64_t daysFromCivil(int y, int m, int d) {
  y -= m <= 2 ? 1 : 0;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const auto yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = static_cast<unsigned>((153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1);
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<std::int64_t>(doe) - 719468;
}

LocalDate civilFromDays(std::int64_t z) {
  z += 719468;
  const std::int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const auto doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  const unsigned d = doy - (153 * mp + 2) / 5 + 1;
  const unsigned m = mp < 10 ? mp + 3 : mp - 9;
  return {static_cast<int>(static_cast<std::int64_t>(yoe) + era * 400 + (m <= 2 ? 1 : 0)), static_cast<int>(m),
          static_cast<int>(d)};
}

LocalDate localDateOf(std::time_t t) {
  std::tm local{};
  localtime_r(&t, &local);
  return {local.tm_year + 1900, local.tm_mon + 1, local.tm_mday};
}

}  // namespace

std::string LocalDate::iso() const { return fmt::format("{:04}-{:02}-{:02}", year, month, day); }

LocalDate localToday() { return localDateOf(std::time(nullptr)); }

LocalDate localDateOfUtc(std::string_view utc) {
  // "YYYY-MM-DDTHH:MM:SSZ", as utcNowIso8601 writes it.
  const auto field = [&](std::size_t at, std::size_t width) {
    int value = -1;
    const char* begin = utc.data() + at;
    const auto [end, error] = std::from_chars(begin, begin + width, value);
    return error == std::errc() && end == begin + width ? value : -1;
  };
  const bool shaped = utc.size() >= 20 && utc[4] == '-' && utc[7] == '-' && utc[10] == 'T' && utc[13] == ':' &&
                      utc[16] == ':' && utc.back() == 'Z';
  const int y = shaped ? field(0, 4) : -1, mo = shaped ? field(5, 2) : -1, d = shaped ? field(8, 2) : -1;
  const int h = shaped ? field(11, 2) : -1, mi = shaped ? field(14, 2) : -1, s = shaped ? field(17, 2) : -1;
  HATTR_THROW_UNLESS(y >= 0 && mo >= 1 && mo <= 12 && d >= 1 && d <= 31 && h >= 0 && h < 24 && mi >= 0 && mi < 60 &&
                         s >= 0 && s <= 60,
                     "time \"{}\": expected a UTC time YYYY-MM-DDTHH:MM:SSZ", utc);
  const std::int64_t seconds = daysFromCivil(y, mo, d) * 86400 + h * 3600 + mi * 60 + s;
  return localDateOf(static_cast<std::time_t>(seconds));
}

LocalDate addDays(const LocalDate& date, int days) {
  return civilFromDays(daysFromCivil(date.year, date.month, date.day) + days);
}

int daysBetween(const LocalDate& from, const LocalDate& to) {
  return static_cast<int>(daysFromCivil(to.year, to.month, to.day) - daysFromCivil(from.year, from.month, from.day));
}

std::string_view timingName(SubjectSchedule::Timing timing) {
  switch (timing) {
    case SubjectSchedule::Timing::kDone: return "done";
    case SubjectSchedule::Timing::kInProgress: return "in-progress";
    case SubjectSchedule::Timing::kAnyTime: return "any-time";
    case SubjectSchedule::Timing::kDue: return "due";
    case SubjectSchedule::Timing::kEarly: return "early";
    case SubjectSchedule::Timing::kOverdue: return "overdue";
  }
  return "?";
}

SubjectSchedule subjectSchedule(const StudyDefinition& study, const std::vector<TrialRecord>& trials,
                                const LocalDate& today) {
  SubjectSchedule out;
  out.sessions = static_cast<int>(study.schedule.size());
  const auto next = std::find_if(trials.begin(), trials.end(),
                                 [](const TrialRecord& t) { return t.status != TrialStatus::kCompleted; });
  if (next == trials.end()) {
    out.timing = SubjectSchedule::Timing::kDone;
    return out;
  }
  out.session = next->plan.session;
  out.day = next->plan.day;
  // A session goes on once any of its trials has been begun.
  const bool begun = std::any_of(trials.begin(), trials.end(), [&](const TrialRecord& t) {
    return t.plan.session == out.session && !t.started_utc.empty();
  });
  if (begun) {
    out.timing = SubjectSchedule::Timing::kInProgress;
    return out;
  }
  // The anchor: the local date the subject's first session began.
  std::optional<LocalDate> first;
  for (const TrialRecord& t : trials) {
    if (t.plan.session == trials.front().plan.session && !t.started_utc.empty()) {
      const LocalDate d = localDateOfUtc(t.started_utc);
      if (!first || d < *first) first = d;
    }
  }
  if (!first) {
    out.timing = SubjectSchedule::Timing::kAnyTime;
    return out;
  }
  out.due = addDays(*first, out.day - trials.front().plan.day);
  const int off = daysBetween(today, *out.due);
  out.timing = off > 0 ? SubjectSchedule::Timing::kEarly
                       : off < 0 ? SubjectSchedule::Timing::kOverdue : SubjectSchedule::Timing::kDue;
  out.days_off = std::abs(off);
  return out;
}

std::string scheduleText(const SubjectSchedule& s) {
  const auto days = [](int n) { return fmt::format("{} day{}", n, n == 1 ? "" : "s"); };
  const std::string session = fmt::format("session {} of {} (day {})", s.session + 1, s.sessions, s.day);
  switch (s.timing) {
    case SubjectSchedule::Timing::kDone: return "done";
    case SubjectSchedule::Timing::kInProgress: return session + " in progress";
    case SubjectSchedule::Timing::kAnyTime: return "next: " + session + ", any time";
    case SubjectSchedule::Timing::kDue: return "next: " + session + ", due today";
    case SubjectSchedule::Timing::kEarly:
      return fmt::format("next: {}, due on {} (in {}): early", session, s.due->iso(), days(s.days_off));
    case SubjectSchedule::Timing::kOverdue:
      return fmt::format("next: {}, due on {} ({} ago): overdue", session, s.due->iso(), days(s.days_off));
  }
  return session;
}

}  // namespace hattr::session
