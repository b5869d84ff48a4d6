#pragma once
/// What a networked device's link did (the udp:// device; any device behind a link reports
/// through Device::link()), for servo-check, device checks and reports. Plain data.

#include <array>
#include <cstdint>

#include "hattr/core/histogram.hpp"
#include "hattr/wire/packet.hpp"

namespace hattr::device {

/// The link's counters and timings since the device was opened.
struct LinkStats {
  DurationHistogram rtt;         ///< network round trip: COMMAND sent → STATE received, minus the server's hold [ns]
  DurationHistogram state_age;   ///< age of the state read() returned: server sampling → client use [ns]
  std::int64_t clock_offset_ns = 0;  ///< server clock − client clock, from the lowest-RTT exchange (NTP-style)
  std::uint64_t commands_sent = 0;    ///< COMMAND packets sent (one a tick while linked)
  std::uint64_t states_received = 0;  ///< accepted STATE packets
  std::uint64_t states_lost = 0;      ///< gaps in the STATE sequence
  std::uint64_t states_late = 0;      ///< arrived after a newer one: dropped, never used
  std::uint64_t held_reads = 0;       ///< reads that bridged with the previous state (no new one)
  std::uint64_t disconnected_reads = 0;  ///< reads with no live session (the loop commanded zero force)
  std::uint64_t reconnects = 0;       ///< new sessions after the first
  std::uint64_t cookies = 0;          ///< COOKIEs the server asked for (one per HELLO attempt)
  wire::DropCounts drops{};           ///< datagrams dropped, by wire::DropReason
};

/// A device's link: its statistics and the rate the far end serves at.
struct DeviceLink {
  LinkStats stats;
  double server_rate_hz = 0.0;
};

}  // namespace hattr::device
