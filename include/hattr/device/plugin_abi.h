/* hattr driver plugin ABI, version 1. Plain C: a plugin may be written in any language that
 * can export a C function. See docs/devices.md for the whole contract and a walk-through.
 *
 * A plugin is a shared object that exports one symbol, HATTR_PLUGIN_ENTRY_SYMBOL, of type
 * hattr_plugin_entry_fn. The host calls it once after dlopen() and reads the returned table:
 * its first two fields are the ABI version and the table's size. This host accepts version 1
 * only and refuses any other with both versions in the message; the size field lets a later
 * version append functions that an older plugin's table does not have.
 *
 * Rules across the line (as CLAP and OpenXR layers have them):
 *   - no C++ types, no exceptions, no allocator mixing: memory is freed by whoever allocated it;
 *   - strings a plugin returns stay owned by the plugin and valid until its next call on the
 *     same device (last_error(NULL) until the next open);
 *   - units are SI and vectors are in hattr's world frame W (docs/units_and_frames.md: paper
 *     plane z = 0, x right, y away from the writer, z up); vendor units and frames are the
 *     plugin's business (the vendor adapter in include/hattr/device/vendor_adapter.hpp does it);
 *   - each function is annotated with the thread that may call it:
 *       [main-thread]  the thread that opened the device, never while the servo loop runs it;
 *       [servo-thread] the servo loop's thread: the host's real-time thread, or, for a device
 *                      that owns the clock, the plugin's own thread inside tick(); such a
 *                      function must not block, allocate, lock or do I/O beyond the device's
 *                      own transport;
 *       [any-thread]   any thread, concurrently with the others.
 */
#ifndef HATTR_DEVICE_PLUGIN_ABI_H
#define HATTR_DEVICE_PLUGIN_ABI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define HATTR_PLUGIN_ABI_VERSION 1u
#define HATTR_PLUGIN_ENTRY_SYMBOL "hattr_plugin_entry"

/* Status codes returned by the plugin's functions. */
enum {
  HATTR_PLUGIN_OK = 0,
  HATTR_PLUGIN_FAULT = 1,        /* the device reports an error (last_error says which) */
  HATTR_PLUGIN_DISCONNECTED = 2, /* the device is gone (unplugged, powered off) */
  HATTR_PLUGIN_TIMEOUT = 3       /* the device did not answer in time */
};

/* How the servo loop is clocked (hattr::device::DeviceClocking). */
enum {
  HATTR_CLOCK_HOST = 0,       /* the host's real-time thread calls read_state / write_force */
  HATTR_CLOCK_SIMULATABLE = 1,/* as HOST, and the host may also run it in simulated time */
  HATTR_CLOCK_DEVICE = 2      /* the plugin calls tick() from its own thread (start_clock) */
};

typedef struct hattr_vec3 {
  double x, y, z;
} hattr_vec3;

/* The pen at one tick [SI, frame W]. */
typedef struct hattr_pen_state {
  double t_s;               /* the device's time of this reading [s] (informational) */
  hattr_vec3 p_m;           /* pen-tip position [m] */
  hattr_vec3 v_m_per_s;     /* pen-tip velocity [m/s] */
  uint32_t buttons;         /* bit 0: stylus button / pen switch */
  int32_t has_force;        /* nonzero: f_measured_N is a force-sensor reading */
  hattr_vec3 f_measured_N;  /* force the user applies through the pen [N] */
  int32_t has_pressure;     /* nonzero: pressure_raw is meaningful */
  double pressure_raw;      /* raw axial pressure, device units */
  int32_t has_tilt;         /* nonzero: azimuth and altitude are meaningful */
  double azimuth_rad;       /* clockwise from +y to the barrel's projection [rad] */
  double altitude_rad;      /* pen axis above the paper [rad] */
} hattr_pen_state;

/* What the device can do [SI, frame W]. */
typedef struct hattr_device_limits {
  int32_t degrees_of_freedom;     /* actuated translational DOF */
  hattr_vec3 workspace_min_m;     /* workspace box in W [m] */
  hattr_vec3 workspace_max_m;
  double peak_force_N;
  double continuous_force_N;
  double max_stiffness_N_per_m;   /* largest stiffness rendered stably at nominal_rate_hz */
  double max_damping_N_s_per_m;
  double nominal_rate_hz;         /* the rate the device is specified for (its clock's rate) */
  double mass_kg;                 /* apparent mass at the tip (passivity bounds) */
  double damping_N_s_per_m;       /* physical damping (passivity bounds) */
} hattr_device_limits;

typedef struct hattr_device_info {
  int32_t clocking;       /* HATTR_CLOCK_* */
  int32_t force_sensor;   /* nonzero: read_state fills f_measured_N */
  int32_t pressure;
  int32_t tilt;
} hattr_device_info;

/* One key=value parameter from the URI plugin:/path/lib.so?key=value&... (UTF-8, unescaped). */
typedef struct hattr_param {
  const char* key;
  const char* value;
} hattr_param;

/* A simulated hand's command (hattr::device::HandCommand) [SI, frame W]. */
typedef struct hattr_hand_command {
  hattr_vec3 p_target_m;
  hattr_vec3 v_target_m_per_s;
  double press_N;
  double azimuth_rad;
  double altitude_rad;
  int32_t pen_down;
} hattr_hand_command;

/* What the host offers the plugin at open. Read abi_version and struct_size first. */
typedef struct hattr_host {
  uint32_t abi_version;  /* HATTR_PLUGIN_ABI_VERSION of the host */
  uint32_t struct_size;  /* sizeof(hattr_host) of the host */
  void* context;         /* passed back to the callbacks below */
  /* [servo-thread] A simulated hand, for simulated devices in tests and demos: fills *out with
   * the hand's command at device time t_s and returns 1, or returns 0 when there is no
   * simulated hand (a person holds the pen). Hardware plugins ignore it. May be NULL. */
  int32_t (*hand_command)(void* context, double t_s, hattr_hand_command* out);
} hattr_host;

/* The host's servo tick, called by a device-clocked plugin once per period from its own
 * thread, with the device's time since start_clock() [ns]. Inside it the host calls read_state
 * and write_force on that same thread. */
typedef void (*hattr_tick_fn)(void* tick_context, int64_t now_ns);

typedef struct hattr_plugin {
  uint32_t abi_version;     /* HATTR_PLUGIN_ABI_VERSION the plugin was built for */
  uint32_t struct_size;     /* sizeof(hattr_plugin) the plugin was built with */
  const char* name;         /* short name, e.g. "openhaptics" */
  const char* description;  /* one line for `hattr devices` */

  /* [main-thread] Opens the device with the URI's parameters. Returns an opaque handle, or
   * NULL on failure; then last_error(NULL) says why. `host` stays valid until close(). */
  void* (*open)(const hattr_param* params, size_t param_count, const hattr_host* host);
  /* [main-thread] Zero force, release the device, free the handle. */
  void (*close)(void* device);
  /* [main-thread] The device's limits and what it offers. Return HATTR_PLUGIN_OK or an error. */
  int32_t (*get_limits)(void* device, hattr_device_limits* out);
  int32_t (*get_info)(void* device, hattr_device_info* out);
  /* [servo-thread] The pen at host loop time now_ns (since the loop started; for a
   * device-clocked plugin, the now_ns it passed to tick()). */
  int32_t (*read_state)(void* device, int64_t now_ns, hattr_pen_state* out);
  /* [servo-thread] Commands the force on the pen [N, W] until the next write. A plugin whose
   * device can should drop the force to zero by itself when no write arrives for a few periods
   * (a hardware watchdog, or, for a device clock, every frame without a write: the vendor
   * adapter does that). */
  int32_t (*write_force)(void* device, const hattr_vec3* force_N);
  /* [main-thread] Device clock only (HATTR_CLOCK_DEVICE): start calling tick(tick_context,
   * now_ns) once per period from the device's thread. NULL for other devices. */
  int32_t (*start_clock)(void* device, hattr_tick_fn tick, void* tick_context);
  /* [main-thread] Stop calling tick; returns once no call is running and the device's force is
   * zero (the vendor adapter writes zero in the device's last frames before stopping). */
  void (*stop_clock)(void* device);
  /* [any-thread] The last error on this device, or of the last failed open when device is
   * NULL. Never NULL: "" when there is none. */
  const char* (*last_error)(void* device);
} hattr_plugin;

/* The one exported function. Returns the plugin's table (static storage), or NULL if it
 * cannot serve a host of host_abi_version. */
typedef const hattr_plugin* (*hattr_plugin_entry_fn)(uint32_t host_abi_version);

#ifdef __cplusplus
}
#endif

#endif /* HATTR_DEVICE_PLUGIN_ABI_H */
