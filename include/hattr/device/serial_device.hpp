#pragma once
/// The open pen on a serial port (docs/hardware.md): serial:///dev/ttyACM0?baud=1000000. The
/// firmware streams a STATE each period on its own clock; this device answers each with a
/// COMMAND, so the servo loop runs on the pen's clock (DeviceClocking::kDeviceClock): a reader
/// thread parses the port and calls the loop's tick once per STATE, and read() and write() run
/// inside that tick. The protocol is include/hattr/openpen/protocol.h, shared with the firmware.
///
///   - open: HELLO until the pen answers with its IDENTITY (an Arduino resets when its port opens,
///     and its boot loader waits about 1.5 s), the protocol version checked (both named when they
///     differ), its constants checked as input;
///   - startClock: START, zeroing the encoders at the home pose once after the pen's power-up
///     (home=once, the default; always, never) — the linkage must rest against its home stops
///     then (docs/hardware.md, "Homing");
///   - read: counts to the pen in W (five-bar kinematics), velocity by a filtered difference, the
///     sensor's normal force as pressure_raw [N] (a planar pen: the table holds the pen up, and
///     its tip counts as lifted 1 mm over the paper when the writer presses less than contact_N);
///   - write: the in-plane force to joint torques by the Jacobian transpose, clamped to the peak,
///     as motor efforts;
///   - no STATE for the pen's watchdog time (20 ms) or a closed port: kDisconnected, and the loop
///     goes on ticking on the host's clock with zero force until it stops.
/// Malformed, out-of-sequence and wrong-version packets are dropped and counted (counters()).

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "hattr/device/device.hpp"
#include "hattr/device/device_uri.hpp"
#include "hattr/device/planar_pen.hpp"

namespace hattr::device {

/// The keys of a serial:// URI.
struct SerialDeviceParams {
  std::filesystem::path port;          ///< the serial device (/dev/ttyACM0, or a pty)
  unsigned baud = 1'000'000;           ///< baud
  /// home: when the encoders are zeroed (the linkage resting at its home pose) as the loop starts.
  enum class Homing { kOnce, kAlways, kNever };
  Homing homing = Homing::kOnce;       ///< once (the default): if the pen has not been homed since power-up
  double handshake_timeout_s = 3.0;    ///< timeout_s: how long open waits for the IDENTITY
  double velocity_cutoff_hz = 100.0;   ///< velocity_hz: the velocity filter's cut-off
  double contact_N = kPlanarContact_N;  ///< contact_N: a press below this is the pen lifted
  double state_timeout_s = 0.0;        ///< state_timeout_s: no STATE this long: the link is lost (0: the pen's watchdog time)
  double max_force_N = 0.0;            ///< max_force_N: lowers the declared forces (0: the pen's own)
  bool lockstep = false;               ///< lockstep=1: hattr-pen-emulator in lockstep (Device::pausableClock)
};

/// Reads and checks a serial:// URI. Unknown keys and bad values throw InputError naming the key,
/// what is accepted and what was given.
SerialDeviceParams serialDeviceParams(const DeviceUri& uri);

/// What each side dropped so far (the device's from its latest STATE).
struct SerialCounters {
  std::uint64_t states = 0;             ///< STATE packets taken
  std::uint64_t malformed = 0;          ///< here: bad CRC or length, unknown type
  std::uint64_t out_of_sequence = 0;    ///< here: a STATE not newer than the last one
  std::uint64_t wrong_version = 0;      ///< here: a frame of another protocol version
  std::uint64_t lost_states = 0;        ///< here: gaps in the STATE sequence
  std::uint64_t unsent_commands = 0;    ///< here: COMMANDs the port did not take
  std::uint32_t device_malformed = 0;   ///< the pen's counts (mod 65536)
  std::uint32_t device_out_of_sequence = 0;
  std::uint32_t device_wrong_version = 0;
  std::uint32_t device_watchdog_trips = 0;
  std::uint32_t device_skipped_states = 0;
};

class SerialDevice final : public Device {
 public:
  /// Opens the port and runs the handshake. Throws InputError for a port that cannot be opened, a
  /// pen that does not answer within the timeout, another protocol version, or constants out of range.
  SerialDevice(const SerialDeviceParams& params, std::string uri_text);
  ~SerialDevice() override;
  SerialDevice(const SerialDevice&) = delete;
  SerialDevice& operator=(const SerialDevice&) = delete;

  DeviceStatus read(std::chrono::nanoseconds now, PenState& out) noexcept override;
  DeviceStatus write(const Vec3& f_on_pen_W) noexcept override;
  const DeviceLimits& limits() const noexcept override;
  DeviceCapabilities capabilities() const noexcept override { return {.pressure = true}; }
  const std::string& uri() const noexcept override;
  DeviceClocking clocking() const noexcept override { return DeviceClocking::kDeviceClock; }
  bool pausableClock() const noexcept override;
  void startClock(DeviceTickFn tick, void* context) override;
  void stopClock() noexcept override;
  std::string faultReason() const override;

  /// The pen's declared constants (from its IDENTITY).
  [[nodiscard]] const PlanarPenSpec& spec() const noexcept;
  /// What both sides dropped so far. Any thread.
  [[nodiscard]] SerialCounters counters() const noexcept;
  /// The efforts of the last COMMAND sent (for tests and the check).
  [[nodiscard]] std::pair<std::int16_t, std::int16_t> lastEfforts() const noexcept;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// Opens serial://PATH?... (see SerialDevice).
std::unique_ptr<Device> openSerialDevice(const DeviceUri& uri, std::string_view uri_text);

/// Help text for serial:// URIs and their keys.
std::string serialDeviceHelp();

}  // namespace hattr::device
