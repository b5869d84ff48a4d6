// hattr.HapticProfile, reading and writing profile files, importing SVC2004 and SUSIG.
//
// Channels come out as float64 NumPy arrays. A stored floating-point channel (t, x, ..., fz,
// cmd_*, guide_*, pressure, azimuth, altitude) is a read-only view into the profile's samples:
// no copy, strided by one sample, valid as long as any array or the profile itself is alive
// (the array keeps the profile alive). Derived channels (speed, |f|) and flags (contact,
// pen_down) are computed, so they are copies. A profile's samples never change once it exists
// in Python (metadata
// included: with_metadata() makes a new profile), so a view never dangles.

#include <filesystem>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.hpp"
#include "hattr/analysis/trial_score.hpp"
#include "hattr/core/channel.hpp"
#include "hattr/core/error.hpp"
#include "hattr/core/haptic_profile.hpp"
#include "hattr/io/profile_csv.hpp"
#include "hattr/io/tablet_import.hpp"

namespace hattr::python {
namespace {

using Array = FloatArray;

static_assert(sizeof(Vec3) == 3 * sizeof(double), "a Vec3 is three packed doubles (the views rely on it)");

/// The address of a stored floating-point channel in one sample; null for derived channels and
/// flags (they are computed, never stored as doubles).
const double* storedValue(const Sample& s, Channel channel) {
  switch (channel) {
    case Channel::kTime: return &s.t_s;
    case Channel::kX: case Channel::kY: case Channel::kZ:
      return s.p_WT.data() + (static_cast<int>(channel) - static_cast<int>(Channel::kX));
    case Channel::kVx: case Channel::kVy: case Channel::kVz:
      return s.v_WT.data() + (static_cast<int>(channel) - static_cast<int>(Channel::kVx));
    case Channel::kFx: case Channel::kFy: case Channel::kFz:
      return s.f_user_W.data() + (static_cast<int>(channel) - static_cast<int>(Channel::kFx));
    case Channel::kCmdFx: case Channel::kCmdFy: case Channel::kCmdFz:
      return s.f_cmd_W.data() + (static_cast<int>(channel) - static_cast<int>(Channel::kCmdFx));
    case Channel::kGuideFx: case Channel::kGuideFy: case Channel::kGuideFz:
      return s.f_guide_W.data() + (static_cast<int>(channel) - static_cast<int>(Channel::kGuideFx));
    case Channel::kPressure: return &s.pressure_raw;
    case Channel::kAzimuth: return &s.tilt_azimuth_rad;
    case Channel::kAltitude: return &s.tilt_altitude_rad;
    default: return nullptr;
  }
}

/// A read-only array over the profile's samples, `columns` doubles from `first` (1: shape (n,),
/// 3: shape (n, 3)); its base is the Python profile, which it keeps alive.
py::array sampleView(const HapticProfile& profile, const double* first, py::ssize_t columns, py::handle owner) {
  const auto n = static_cast<py::ssize_t>(profile.size());
  const auto stride = static_cast<py::ssize_t>(sizeof(Sample));
  py::array view = columns == 1
                       ? py::array(py::dtype::of<double>(), {n}, {stride}, first, owner)
                       : py::array(py::dtype::of<double>(), {n, columns},
                                   {stride, static_cast<py::ssize_t>(sizeof(double))}, first, owner);
  view.attr("setflags")(py::arg("write") = false);
  return view;
}

/// One channel by name: a view when it is stored as doubles, else a copy.
py::array channelArray(const py::object& self, const std::string& name) {
  const auto& profile = self.cast<const HapticProfile&>();
  const std::optional<Channel> channel = channelFromName(name);
  if (!channel) return py::array(py::cast(profile.channel(name)));  // throws InputError naming the channels
  if (!profile.hasChannel(*channel)) return py::array(py::cast(profile.channel(*channel)));  // throws
  const double* first = profile.empty() ? nullptr : storedValue(profile[0], *channel);
  if (first == nullptr) return Array(py::cast(profile.channel(*channel)));
  return sampleView(profile, first, 1, self);
}

/// A 3-vector field of every sample as an (n, 3) view.
py::array vectorView(const py::object& self, Vec3 Sample::*field) {
  const auto& profile = self.cast<const HapticProfile&>();
  if (profile.empty()) return Array(std::vector<py::ssize_t>{0, 3});
  return sampleView(profile, (profile[0].*field).data(), 3, self);
}

/// A flag channel (contact, pen_down) as a bool array, a copy.
py::array_t<bool> flagArray(const HapticProfile& profile, Channel channel) {
  py::array_t<bool> flags(static_cast<py::ssize_t>(profile.size()));
  auto out = flags.mutable_unchecked<1>();
  for (std::size_t i = 0; i < profile.size(); ++i) out(static_cast<py::ssize_t>(i)) = channelValue(profile[i], channel) != 0.0;
  return flags;
}

/// The names of the channels this profile carries, in file-column order.
std::vector<std::string> channelNames(const HapticProfile& profile) {
  std::vector<std::string> names;
  for (const ChannelInfo& info : allChannels()) {
    if (profile.hasChannel(info.channel)) names.emplace_back(info.name);
  }
  return names;
}

/// Metadata as one flat dict: the named fields, then every extra key.
py::dict metadataDict(const ProfileMetadata& m) {
  py::dict d;
  d["subject"] = m.subject;
  d["skill"] = m.skill;
  d["device"] = m.device;
  d["source"] = m.source;
  d["created_utc"] = m.created_utc;
  d["nominal_rate_hz"] = m.nominal_rate_hz;
  for (const auto& [key, value] : m.extra) d[py::str(key)] = value;
  return d;
}

/// The inverse of metadataDict: named fields by name, everything else as text in extra. Values
/// are text or numbers (written as text); nominal_rate_hz a number. InputError otherwise.
ProfileMetadata metadataFromDict(const py::dict& d) {
  ProfileMetadata m;
  for (const auto& [key_object, value] : d) {
    const std::string key = py::str(key_object);
    const bool number = (py::isinstance<py::int_>(value) || py::isinstance<py::float_>(value)) &&
                        !py::isinstance<py::bool_>(value);
    if (key == "nominal_rate_hz") {
      HATTR_THROW_UNLESS(number, "metadata: nominal_rate_hz: expected a number [Hz], got {}", std::string(py::repr(value)));
      m.nominal_rate_hz = value.cast<double>();
      continue;
    }
    HATTR_THROW_UNLESS(number || py::isinstance<py::str>(value), "metadata: {}: expected text or a number, got {}", key,
                       std::string(py::repr(value)));
    const std::string text = py::str(value);
    if (key == "subject") m.subject = text;
    else if (key == "skill") m.skill = text;
    else if (key == "device") m.device = text;
    else if (key == "source") m.source = text;
    else if (key == "created_utc") m.created_utc = text;
    else m.extra[key] = text;
  }
  return m;
}

/// An optional (n, 3) numeric array (InputError naming it when the shape is wrong).
std::optional<Array> vectorsOf(const py::object& values, py::ssize_t n, std::string_view name) {
  if (values.is_none()) return std::nullopt;
  Array array = floatArray(values, name);
  const bool ok = array.ndim() == 2 && array.shape(0) == n && array.shape(1) == 3;
  HATTR_THROW_UNLESS(ok, "HapticProfile.from_arrays: {} must have shape ({}, 3), one row per time stamp; got {}", name,
                     n, std::string(py::str(array.attr("shape"))));
  return array;
}

Vec3 rowOf(const std::optional<Array>& array, py::ssize_t row) {
  if (!array) return Vec3::Zero();
  return {array->at(row, 0), array->at(row, 1), array->at(row, 2)};
}

/// A profile from arrays (SI units); velocity by finite differences when not given.
HapticProfile profileFromArrays(const py::object& t_s, const py::object& p_WT_m, const py::object& v_WT_m_per_s,
                                const py::object& f_user_W_N, const py::object& pen_down,
                                const std::optional<py::dict>& metadata) {
  const Array times = floatArray(t_s, "t_s");
  HATTR_THROW_UNLESS(times.ndim() == 1, "HapticProfile.from_arrays: t_s must be one-dimensional; got {} dimensions",
                     times.ndim());
  const py::ssize_t n = times.shape(0);
  const std::optional<Array> positions = vectorsOf(p_WT_m, n, "p_WT_m");
  HATTR_THROW_UNLESS(positions.has_value(), "HapticProfile.from_arrays: p_WT_m is required");
  const std::optional<Array> velocities = vectorsOf(v_WT_m_per_s, n, "v_WT_m_per_s");
  const std::optional<Array> forces = vectorsOf(f_user_W_N, n, "f_user_W_N");
  std::optional<py::array_t<bool>> down;
  if (!pen_down.is_none()) {
    const py::array flags = py::array::ensure(pen_down);
    HATTR_THROW_UNLESS(flags && flags.dtype().kind() == 'b' && flags.ndim() == 1 && flags.shape(0) == n,
                       "HapticProfile.from_arrays: pen_down must be booleans of shape ({},); got {}", n,
                       flags ? fmt::format("{} of shape {}", std::string(py::str(flags.dtype())),
                                           std::string(py::str(flags.attr("shape"))))
                             : std::string(py::str(py::type::of(pen_down))));
    down = py::array_t<bool>::ensure(flags);
  }
  std::vector<Sample> samples(static_cast<std::size_t>(n));
  for (py::ssize_t i = 0; i < n; ++i) {
    Sample& s = samples[static_cast<std::size_t>(i)];
    s.t_s = times.at(i);
    s.p_WT = rowOf(positions, i);
    s.v_WT = rowOf(velocities, i);
    s.f_user_W = rowOf(forces, i);
    s.pen_down = down ? down->at(i) : true;
    s.in_contact = s.pen_down;
  }
  return HapticProfile::fromSamples(metadata ? metadataFromDict(*metadata) : ProfileMetadata{}, {}, std::move(samples),
                                    !velocities.has_value());
}

/// A tablet calibration: the format's defaults, overridden by a dict or a JSON file.
using CalibrationOverrides = std::optional<std::variant<py::dict, std::filesystem::path>>;
io::TabletCalibration calibrationOf(const CalibrationOverrides& overrides, const io::TabletCalibration& defaults) {
  if (!overrides) return defaults;
  if (const auto* fields = std::get_if<py::dict>(&*overrides)) {
    return io::parseCalibration(fromPython(*fields).dump(), "calibration dict", defaults);
  }
  return io::loadCalibration(std::get<std::filesystem::path>(*overrides), defaults);
}

/// HapticProfile: building one, its metadata, its size and rates.
void bindProfileBasics(py::class_<HapticProfile>& profile) {
  profile
      .def_static("from_arrays", &profileFromArrays, py::arg("t_s"), py::arg("p_WT_m"), py::kw_only(),
                  py::arg("v_WT_m_per_s") = py::none(), py::arg("f_user_W_N") = py::none(),
                  py::arg("pen_down") = py::none(), py::arg("metadata") = py::none(),
                  "A profile from arrays: times t_s [s] (n,), strictly increasing; pen-tip positions p_WT_m [m] "
                  "(n, 3); velocities [m/s] (n, 3), by finite differences when omitted; the force the pen exerts "
                  "[N] (n, 3), zero when omitted; pen_down flags (n,), all down when omitted. Copies the data.")
      .def("__len__", &HapticProfile::size)
      .def("__eq__", [](const HapticProfile& a, const HapticProfile& b) { return a == b; }, py::is_operator())
      .def("__repr__",
           [](const HapticProfile& p) {
             return fmt::format("<hattr.HapticProfile subject='{}' skill='{}' samples={} duration_s={:.3f}>",
                                p.metadata().subject, p.metadata().skill, p.size(), p.duration_s());
           })
      .def_property_readonly(
          "metadata", [](const HapticProfile& p) { return metadataDict(p.metadata()); },
          "Metadata as a dict (a copy): subject, skill, device, source, created_utc, nominal_rate_hz [Hz] and "
          "every other key (mode, trial, writing_begin_s, ...) as text. A profile never changes: "
          "with_metadata() gives a new one.")
      .def(
          "with_metadata",
          [](const HapticProfile& p, const py::dict& metadata) {
            HapticProfile copy = p;
            copy.metadata() = metadataFromDict(metadata);
            return copy;
          },
          py::arg("metadata"),
          "A copy of this profile with these metadata (a dict as `metadata` gives: text or numbers; "
          "nominal_rate_hz a number [Hz]).")
      .def_property_readonly(
          "raw_channels", [](const HapticProfile& p) {
            return py::dict(py::arg("pressure") = p.rawChannels().pressure, py::arg("tilt") = p.rawChannels().tilt);
          },
          "Which raw device channels the profile carries: {'pressure': bool, 'tilt': bool}.")
      .def_property_readonly("duration_s", &HapticProfile::duration_s, "Last time minus first [s].")
      .def_property_readonly("measured_rate_hz", &HapticProfile::measuredRate_hz, "(samples − 1) / duration [Hz].")
      .def_property_readonly("pen_down_count", &HapticProfile::penDownCount, "Samples with the pen down.");
}

/// HapticProfile: its channels as NumPy arrays (views of stored ones, copies of the rest).
void bindProfileChannels(py::class_<HapticProfile>& profile) {
  profile
      .def_property_readonly("channel_names", &channelNames, "The channels this profile carries, in file order.")
      .def("channel", &channelArray, py::arg("name"),
           "One channel by name ('t', 'x', 'fz', '|f|', 'pen_down', ...), SI units, shape (n,). Stored "
           "channels are read-only views; derived ones and flags are copies. InputError for an unknown name.")
      .def(
          "channels",
          [](const py::object& self) {
            py::dict d;
            for (const std::string& name : channelNames(self.cast<const HapticProfile&>())) {
              d[py::str(name)] = channelArray(self, name);
            }
            return d;
          },
          "Every channel the profile carries, name → array (a dict pandas.DataFrame takes as it is).")
      .def_property_readonly("t_s", [](const py::object& self) { return channelArray(self, "t"); },
                             "Sample times [s], (n,), a view.")
      .def_property_readonly("p_WT_m", [](const py::object& self) { return vectorView(self, &Sample::p_WT); },
                             "Pen-tip positions in W [m], (n, 3), a view.")
      .def_property_readonly("v_WT_m_per_s", [](const py::object& self) { return vectorView(self, &Sample::v_WT); },
                             "Pen-tip velocities in W [m/s], (n, 3), a view.")
      .def_property_readonly("f_user_W_N", [](const py::object& self) { return vectorView(self, &Sample::f_user_W); },
                             "Force the pen (the user) exerts on the paper, in W [N], (n, 3), a view.")
      .def_property_readonly("f_cmd_W_N", [](const py::object& self) { return vectorView(self, &Sample::f_cmd_W); },
                             "Total force the device commands on the pen, in W [N], (n, 3), a view.")
      .def_property_readonly("f_guide_W_N",
                             [](const py::object& self) { return vectorView(self, &Sample::f_guide_W); },
                             "The guidance part of f_cmd_W_N [N], (n, 3), a view.")
      .def_property_readonly(
          "pen_down", [](const HapticProfile& p) { return flagArray(p, Channel::kPenDown); },
          "Pen-down flags, (n,) bool, a copy.")
      .def_property_readonly(
          "in_contact", [](const HapticProfile& p) { return flagArray(p, Channel::kContact); },
          "Pen-tip-on-paper flags, (n,) bool, a copy.")
      .def_property_readonly(
          "writing_span_s",
          [](const HapticProfile& p) {
            const analysis::TimeSpan span = analysis::writingSpan(p);
            return py::make_tuple(span.begin_s, span.end_s);
          },
          "(begin, end) [s]: first pen-down to last pen-up when the trial recorded them, else the whole "
          "profile; the span the paper's scores use.");
}

/// The class hattr.HapticProfile.
void bindProfileClass(py::module_& m) {
  py::class_<HapticProfile> profile(m, "HapticProfile",
                                    "One person performing one task: servo-rate samples (SI units, world frame W) and "
                                    "metadata. Channels are float64 NumPy arrays; stored ones are read-only views.");
  bindProfileBasics(profile);
  bindProfileChannels(profile);
}

/// Reading and writing profile files, importing SVC2004 and SUSIG.
void bindProfileFunctions(py::module_& m) {
  m.def("read_profile", py::overload_cast<const std::filesystem::path&>(&io::readProfileCsv), py::arg("path"),
        "Reads a hattr profile CSV file (docs/file-formats.md); millimetre and millisecond columns become SI. "
        "InputError naming file, line and column for anything wrong.");
  m.def(
      "write_profile",
      [](const HapticProfile& profile, const std::filesystem::path& path, bool overwrite) {
        io::writeProfileCsv(profile, path, overwrite ? hattr::Overwrite::kReplace : hattr::Overwrite::kRefuse);
      },
      py::arg("profile"), py::arg("path"), py::kw_only(), py::arg("overwrite") = false,
      "Writes a profile CSV (SI units, reads back bit for bit), atomically. An existing file is kept and "
      "InputError raised unless overwrite=True.");
  m.def(
      "import_svc2004",
      [](const std::filesystem::path& path, const CalibrationOverrides& calibration) {
        return io::importSvc2004(path, calibrationOf(calibration, io::svc2004Calibration()));
      },
      py::arg("path"), py::kw_only(), py::arg("calibration") = py::none(),
      "Imports an SVC2004 .TXT recording as a profile in SI units. calibration: None (the format's defaults), "
      "a dict of fields to override ({'pressure_max_N': 3.5}) or a JSON file (docs/file-formats.md).");
  m.def(
      "import_susig",
      [](const std::filesystem::path& path, const CalibrationOverrides& calibration) {
        return io::importSusig(path, calibrationOf(calibration, io::susigCalibration()));
      },
      py::arg("path"), py::kw_only(), py::arg("calibration") = py::none(),
      "Imports a SUSIG recording as a profile in SI units; calibration as for import_svc2004.");
}

}  // namespace

void bindProfiles(py::module_& m) {
  bindProfileClass(m);
  bindProfileFunctions(m);
}

}  // namespace hattr::python
