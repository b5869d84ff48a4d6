#ifndef HATTR_OPENPEN_PROTOCOL_H
#define HATTR_OPENPEN_PROTOCOL_H
/* The open pen's serial protocol (docs/hardware.md): one C99 header shared, unchanged, by the
 * reference firmware (firmware/openpen, avr-gcc) and by hattr's serial:// device, so both sides
 * frame, check and decode packets with the same code.
 *
 * A frame: 0xA5 0x5A, protocol version (u8), type (u8), payload length (u8), the payload (its
 * length fixed by the type), CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF) over version .. the
 * payload's last byte, little-endian. Every multi-byte field is little-endian; floats are IEEE 754
 * binary32. Nothing here allocates or depends on the platform's byte order. */

#include <stdint.h>
#include <string.h>

#ifdef __cplusplus
extern "C" {
#endif

#define HPEN_SYNC0 0xA5u
#define HPEN_SYNC1 0x5Au
/* (Overridden only to build the version-mismatch test firmware: tests/openpen.) */
#ifndef HPEN_PROTOCOL_VERSION
#define HPEN_PROTOCOL_VERSION 1u
#endif
#define HPEN_HEADER_BYTES 5u
#define HPEN_CRC_BYTES 2u
#define HPEN_MODEL_BYTES 12u

/* The packet types. Host to device: HELLO, START, COMMAND, STOP. Device to host: IDENTITY, STATE. */
enum hpen_type {
  HPEN_HELLO = 1,    /* who are you? (answered with IDENTITY, whatever the version) */
  HPEN_IDENTITY = 2, /* identity, geometry, motor and sensor constants, limits */
  HPEN_START = 3,    /* begin streaming STATE at the device's rate; may zero the encoders first */
  HPEN_STATE = 4,    /* the device's state, once per period on its own clock */
  HPEN_COMMAND = 5,  /* the motor efforts answering one STATE */
  HPEN_STOP = 6      /* motors off, stop streaming */
};

/* Payload lengths by type. */
#define HPEN_HELLO_BYTES 4u
#define HPEN_IDENTITY_BYTES 64u
#define HPEN_START_BYTES 4u
#define HPEN_STATE_BYTES 30u
#define HPEN_COMMAND_BYTES 8u
#define HPEN_STOP_BYTES 4u
#define HPEN_MAX_PAYLOAD_BYTES HPEN_IDENTITY_BYTES
#define HPEN_MAX_FRAME_BYTES (HPEN_HEADER_BYTES + HPEN_MAX_PAYLOAD_BYTES + HPEN_CRC_BYTES)

/* STATE flags. */
#define HPEN_STATE_MOTORS_ON 0x01u   /* the H-bridge is enabled and driving the last command */
#define HPEN_STATE_WATCHDOG 0x02u    /* no valid COMMAND for watchdog_ms: motors off until one comes */
#define HPEN_STATE_BUTTON 0x04u      /* the pen's button is pressed */
/* COMMAND flags. */
#define HPEN_COMMAND_ENABLE 0x01u    /* drive the motors (else: efforts ignored, motors off) */
/* IDENTITY status. */
#define HPEN_IDENTITY_HOMED 0x01u    /* the encoders were zeroed at the home pose since power-up */
/* START flags. */
#define HPEN_START_ZERO_ENCODERS 0x01u /* the linkage is at its home pose: counts become zero */

/* The effort scale: +-32767 is the motor's peak torque, in either direction. */
#define HPEN_EFFORT_FULL 32767

struct hpen_hello {
  uint32_t nonce; /* echoed by IDENTITY */
};

/* What the device is (IEEE 1918.1.1's capability exchange, for a planar pantograph). A five-bar:
 * two motors on the base line, `base_separation_m` apart, each driving a proximal link of
 * `proximal_m`; two distal links of `distal_m` meet at the pen. Joint angles from the base line,
 * counter-clockwise, in the device frame D (x along the base line from motor 0 to motor 1, y
 * towards the pen); at the home pose the joints are at home_q0/home_q1. */
struct hpen_identity {
  uint32_t nonce;              /* the HELLO's */
  uint16_t firmware_build;     /* the firmware's own build number */
  char model[HPEN_MODEL_BYTES];/* NUL-padded, e.g. "openpen-5bar" */
  uint16_t state_rate_hz;      /* STATE packets per second */
  uint16_t watchdog_ms;        /* motors off after this long without a valid COMMAND */
  float base_separation_m;
  float proximal_m;
  float distal_m;
  float home_q0_rad;
  float home_q1_rad;
  uint32_t counts_per_joint_rev; /* encoder counts (x4 decoding) per turn of a joint */
  float peak_torque_Nm;        /* joint torque at HPEN_EFFORT_FULL */
  float continuous_torque_Nm;  /* joint torque the motor sustains */
  float sensor_N_per_count;    /* pen force sensor: newtons per ADC count above its zero */
  uint16_t sensor_zero_count;  /* the sensor's nominal reading at no load */
  uint16_t sensor_max_count;   /* the ADC's full scale (the sensor's rated load lies below it) */
  uint8_t motor_sign;          /* bit i: motor i's positive effort turns its joint clockwise */
  uint8_t status;              /* HPEN_IDENTITY_* */
};

struct hpen_start {
  uint8_t flags; /* HPEN_START_* */
};

struct hpen_state {
  uint16_t seq;          /* one more than the last STATE's (wraps) */
  uint32_t time_us;      /* the device's clock when the state was sampled (wraps) */
  int32_t count0;        /* encoder counts since the home pose, joint 0 */
  int32_t count1;
  uint16_t sensor;       /* the pen force sensor's ADC reading */
  uint8_t flags;         /* HPEN_STATE_* */
  /* What the device dropped so far, counted since reset (wrap at 65535). */
  uint16_t rx_malformed;       /* bad CRC, bad length, unknown type */
  uint16_t rx_out_of_sequence; /* a COMMAND not answering the last or last-but-one STATE, or repeated */
  uint16_t rx_wrong_version;   /* a frame of another protocol version */
  uint16_t watchdog_trips;     /* times the watchdog turned the motors off */
  uint16_t tx_skipped;         /* STATE packets not sent because the UART was still busy */
};

struct hpen_command {
  uint16_t seq;      /* the seq of the STATE this answers */
  int16_t effort0;   /* motor 0, HPEN_EFFORT_FULL = peak torque */
  int16_t effort1;
  uint8_t flags;     /* HPEN_COMMAND_* */
};

/* ---- CRC-16/CCITT-FALSE, one byte at a time (no table: cheap on an AVR too) ---- */

static inline uint16_t hpen_crc_update(uint16_t crc, uint8_t byte) {
  uint8_t x = (uint8_t)((crc >> 8) ^ byte);
  x ^= (uint8_t)(x >> 4);
  return (uint16_t)((crc << 8) ^ ((uint16_t)x << 12) ^ ((uint16_t)x << 5) ^ (uint16_t)x);
}

static inline uint16_t hpen_crc(const uint8_t* bytes, uint16_t n) {
  uint16_t crc = 0xFFFFu;
  for (uint16_t i = 0; i < n; ++i) crc = hpen_crc_update(crc, bytes[i]);
  return crc;
}

/* ---- little-endian fields ---- */

static inline void hpen_put_u16(uint8_t* p, uint16_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); }
static inline void hpen_put_u32(uint8_t* p, uint32_t v) {
  p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24);
}
static inline void hpen_put_f32(uint8_t* p, float v) { uint32_t u; memcpy(&u, &v, 4); hpen_put_u32(p, u); }
static inline uint16_t hpen_get_u16(const uint8_t* p) { return (uint16_t)(p[0] | ((uint16_t)p[1] << 8)); }
static inline uint32_t hpen_get_u32(const uint8_t* p) {
  return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static inline float hpen_get_f32(const uint8_t* p) { uint32_t u = hpen_get_u32(p); float v; memcpy(&v, &u, 4); return v; }

/* The payload length a type has; 0 for an unknown type. */
static inline uint8_t hpen_payload_bytes(uint8_t type) {
  switch (type) {
    case HPEN_HELLO: return HPEN_HELLO_BYTES;
    case HPEN_IDENTITY: return HPEN_IDENTITY_BYTES;
    case HPEN_START: return HPEN_START_BYTES;
    case HPEN_STATE: return HPEN_STATE_BYTES;
    case HPEN_COMMAND: return HPEN_COMMAND_BYTES;
    case HPEN_STOP: return HPEN_STOP_BYTES;
    default: return 0;
  }
}

/* Frames a payload into `out` (room for HPEN_MAX_FRAME_BYTES) with `version`; returns the frame's length. */
static inline uint8_t hpen_frame(uint8_t* out, uint8_t version, uint8_t type, const uint8_t* payload, uint8_t n) {
  out[0] = HPEN_SYNC0;
  out[1] = HPEN_SYNC1;
  out[2] = version;
  out[3] = type;
  out[4] = n;
  memcpy(out + HPEN_HEADER_BYTES, payload, n);
  hpen_put_u16(out + HPEN_HEADER_BYTES + n, hpen_crc(out + 2, (uint16_t)(3u + n)));
  return (uint8_t)(HPEN_HEADER_BYTES + n + HPEN_CRC_BYTES);
}

/* ---- payloads: encode into `p` (its type's length), decode from it ---- */

static inline void hpen_encode_hello(uint8_t* p, const struct hpen_hello* m) { hpen_put_u32(p, m->nonce); }
static inline void hpen_decode_hello(const uint8_t* p, struct hpen_hello* m) { m->nonce = hpen_get_u32(p); }

static inline void hpen_encode_start(uint8_t* p, const struct hpen_start* m) {
  p[0] = m->flags; p[1] = 0; p[2] = 0; p[3] = 0;
}
static inline void hpen_decode_start(const uint8_t* p, struct hpen_start* m) { m->flags = p[0]; }

static inline void hpen_encode_identity(uint8_t* p, const struct hpen_identity* m) {
  hpen_put_u32(p + 0, m->nonce);
  hpen_put_u16(p + 4, m->firmware_build);
  memcpy(p + 6, m->model, HPEN_MODEL_BYTES);
  hpen_put_u16(p + 18, m->state_rate_hz);
  hpen_put_u16(p + 20, m->watchdog_ms);
  hpen_put_f32(p + 22, m->base_separation_m);
  hpen_put_f32(p + 26, m->proximal_m);
  hpen_put_f32(p + 30, m->distal_m);
  hpen_put_f32(p + 34, m->home_q0_rad);
  hpen_put_f32(p + 38, m->home_q1_rad);
  hpen_put_u32(p + 42, m->counts_per_joint_rev);
  hpen_put_f32(p + 46, m->peak_torque_Nm);
  hpen_put_f32(p + 50, m->continuous_torque_Nm);
  hpen_put_f32(p + 54, m->sensor_N_per_count);
  hpen_put_u16(p + 58, m->sensor_zero_count);
  hpen_put_u16(p + 60, m->sensor_max_count);
  p[62] = m->motor_sign;
  p[63] = m->status;
}
static inline void hpen_decode_identity(const uint8_t* p, struct hpen_identity* m) {
  memset(m, 0, sizeof *m);
  m->nonce = hpen_get_u32(p + 0);
  m->firmware_build = hpen_get_u16(p + 4);
  memcpy(m->model, p + 6, HPEN_MODEL_BYTES);
  m->state_rate_hz = hpen_get_u16(p + 18);
  m->watchdog_ms = hpen_get_u16(p + 20);
  m->base_separation_m = hpen_get_f32(p + 22);
  m->proximal_m = hpen_get_f32(p + 26);
  m->distal_m = hpen_get_f32(p + 30);
  m->home_q0_rad = hpen_get_f32(p + 34);
  m->home_q1_rad = hpen_get_f32(p + 38);
  m->counts_per_joint_rev = hpen_get_u32(p + 42);
  m->peak_torque_Nm = hpen_get_f32(p + 46);
  m->continuous_torque_Nm = hpen_get_f32(p + 50);
  m->sensor_N_per_count = hpen_get_f32(p + 54);
  m->sensor_zero_count = hpen_get_u16(p + 58);
  m->sensor_max_count = hpen_get_u16(p + 60);
  m->motor_sign = p[62];
  m->status = p[63];
}

static inline void hpen_encode_state(uint8_t* p, const struct hpen_state* m) {
  hpen_put_u16(p + 0, m->seq);
  hpen_put_u32(p + 2, m->time_us);
  hpen_put_u32(p + 6, (uint32_t)m->count0);
  hpen_put_u32(p + 10, (uint32_t)m->count1);
  hpen_put_u16(p + 14, m->sensor);
  p[16] = m->flags;
  p[17] = 0;
  hpen_put_u16(p + 18, m->rx_malformed);
  hpen_put_u16(p + 20, m->rx_out_of_sequence);
  hpen_put_u16(p + 22, m->rx_wrong_version);
  hpen_put_u16(p + 24, m->watchdog_trips);
  hpen_put_u16(p + 26, m->tx_skipped);
  p[28] = 0;
  p[29] = 0;
}
static inline void hpen_decode_state(const uint8_t* p, struct hpen_state* m) {
  m->seq = hpen_get_u16(p + 0);
  m->time_us = hpen_get_u32(p + 2);
  m->count0 = (int32_t)hpen_get_u32(p + 6);
  m->count1 = (int32_t)hpen_get_u32(p + 10);
  m->sensor = hpen_get_u16(p + 14);
  m->flags = p[16];
  m->rx_malformed = hpen_get_u16(p + 18);
  m->rx_out_of_sequence = hpen_get_u16(p + 20);
  m->rx_wrong_version = hpen_get_u16(p + 22);
  m->watchdog_trips = hpen_get_u16(p + 24);
  m->tx_skipped = hpen_get_u16(p + 26);
}

static inline void hpen_encode_command(uint8_t* p, const struct hpen_command* m) {
  hpen_put_u16(p + 0, m->seq);
  hpen_put_u16(p + 2, (uint16_t)m->effort0);
  hpen_put_u16(p + 4, (uint16_t)m->effort1);
  p[6] = m->flags;
  p[7] = 0;
}
static inline void hpen_decode_command(const uint8_t* p, struct hpen_command* m) {
  m->seq = hpen_get_u16(p + 0);
  m->effort0 = (int16_t)hpen_get_u16(p + 2);
  m->effort1 = (int16_t)hpen_get_u16(p + 4);
  m->flags = p[6];
}

/* ---- the receiver: one byte at a time, resynchronizing on the sync bytes ---- */

enum hpen_event {
  HPEN_NONE = 0,          /* need more bytes */
  HPEN_FRAME,             /* a whole, checked frame of our version: type and payload in the parser */
  HPEN_BAD_CRC,           /* a frame whose CRC does not match (dropped) */
  HPEN_BAD_LENGTH,        /* a known type with another length, or an unknown type (dropped) */
  HPEN_WRONG_VERSION      /* a checked frame of another version: version, type and payload kept */
};

struct hpen_parser {
  uint8_t buffer[HPEN_MAX_FRAME_BYTES];
  uint8_t fill;
  uint8_t expected; /* the whole frame's length once the header is in; 0 before */
};

static inline void hpen_parser_reset(struct hpen_parser* p) { p->fill = 0; p->expected = 0; }
static inline uint8_t hpen_parser_version(const struct hpen_parser* p) { return p->buffer[2]; }
static inline uint8_t hpen_parser_type(const struct hpen_parser* p) { return p->buffer[3]; }
static inline const uint8_t* hpen_parser_payload(const struct hpen_parser* p) { return p->buffer + HPEN_HEADER_BYTES; }

/* After a dropped frame, the bytes that followed its first one may hold the next frame's start (a
 * lost byte makes a frame swallow the next one's sync): keeps them from the first sync on. A kept
 * header that does not fit, or a kept whole frame, is dropped too (rare: a frame inside a frame). */
static inline void hpen_parser_resync(struct hpen_parser* p, uint8_t had) {
  uint8_t i = 1;
  while (i < had && !(p->buffer[i] == HPEN_SYNC0 && (i + 1u == had || p->buffer[i + 1u] == HPEN_SYNC1))) ++i;
  const uint8_t keep = (uint8_t)(had - i);
  memmove(p->buffer, p->buffer + i, keep);
  p->fill = keep;
  p->expected = 0;
  if (keep >= HPEN_HEADER_BYTES) {
    const uint8_t n = hpen_payload_bytes(p->buffer[3]);
    p->expected = (uint8_t)(HPEN_HEADER_BYTES + n + HPEN_CRC_BYTES);
    if (n == 0 || n != p->buffer[4] || keep >= p->expected) hpen_parser_reset(p);
  }
}

/* Feeds one byte; returns what it completed. A length that does not fit its type is refused at
 * the header, so a corrupted length never makes the receiver wait for bytes that will not come.
 * The version is checked after the CRC, so a corrupted version byte reads as a bad CRC. */
static inline enum hpen_event hpen_parser_feed(struct hpen_parser* p, uint8_t byte) {
  if (p->fill == 0) {
    if (byte == HPEN_SYNC0) p->buffer[p->fill++] = byte;
    return HPEN_NONE;
  }
  if (p->fill == 1) {
    if (byte == HPEN_SYNC1) p->buffer[p->fill++] = byte;
    else p->fill = (byte == HPEN_SYNC0) ? 1u : 0u;
    return HPEN_NONE;
  }
  p->buffer[p->fill++] = byte;
  if (p->fill == HPEN_HEADER_BYTES) {
    const uint8_t n = hpen_payload_bytes(p->buffer[3]);
    if (n == 0 || n != p->buffer[4]) {
      hpen_parser_resync(p, HPEN_HEADER_BYTES);
      return HPEN_BAD_LENGTH;
    }
    p->expected = (uint8_t)(HPEN_HEADER_BYTES + n + HPEN_CRC_BYTES);
    return HPEN_NONE;
  }
  if (p->expected == 0 || p->fill < p->expected) return HPEN_NONE;
  {
    const uint8_t n = p->buffer[4];
    const uint16_t crc = hpen_get_u16(p->buffer + HPEN_HEADER_BYTES + n);
    if (crc != hpen_crc(p->buffer + 2, (uint16_t)(3u + n))) {
      hpen_parser_resync(p, p->expected);
      return HPEN_BAD_CRC;
    }
    p->fill = 0;
    p->expected = 0;
    return p->buffer[2] == HPEN_PROTOCOL_VERSION ? HPEN_FRAME : HPEN_WRONG_VERSION;
  }
}

#ifdef __cplusplus
}
#endif

#endif /* HATTR_OPENPEN_PROTOCOL_H */
