/* The open pen's reference firmware (docs/hardware.md): an ATmega328P (Arduino Uno) driving a
 * two-motor five-bar pantograph through a TB6612FNG H-bridge, reading two quadrature encoders and
 * the pen's force sensor, and speaking the serial protocol of include/hattr/openpen/protocol.h at
 * 1 Mbaud.
 *
 * Pins (Arduino numbering in brackets):
 *   UART          PD0 RX [0], PD1 TX [1]
 *   encoder 0     A PD4 [4], B PD5 [5]      encoder 1  A PD6 [6], B PD7 [7]   (pin-change IRQ)
 *   motor 0       PWM OC2A PB3 [11], AIN1 PB0 [8], AIN2 PB1 [9]
 *   motor 1       PWM OC2B PD3 [3],  BIN1 PB2 [10], BIN2 PB4 [12]
 *   H-bridge STBY PD2 [2] (pulled down on the board: a reset chip leaves the motors off)
 *   pen button    PC1 [A1] to ground (internal pull-up)
 *   force sensor  ADC0 PC0 [A0], AVCC reference
 *
 * Time: Timer1 ticks the servo clock at OPENPEN_STATE_RATE_HZ; each tick samples the encoders and
 * the sensor and, while streaming, sends one STATE. The main loop parses what the host sent. The
 * watchdog turns the motors off when no valid COMMAND came for OPENPEN_WATCHDOG_MS; the chip's own
 * watchdog resets it (pins float, STBY pulled down: motors off) if the main loop ever hangs. */

#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <avr/wdt.h>
#include <stdint.h>
#include <string.h>

#include "config.h"
#include "hattr/openpen/protocol.h"

#ifndef F_CPU
#error "F_CPU must be defined (16000000UL for an Arduino Uno)"
#endif

/* ---- the encoders: x4 quadrature decoding on pin change ---- */

static volatile int32_t g_count[2];
static volatile uint8_t g_last_pins;

/* Change of count for (previous AB << 2 | new AB): +1 one way round the Gray cycle, -1 the other,
 * 0 for no change or a skipped state (two edges at once cannot be told apart). */
static const int8_t kQuadrature[16] = {0, 1, -1, 0, -1, 0, 0, 1, 1, 0, 0, -1, 0, -1, 1, 0};

ISR(PCINT2_vect) {
  const uint8_t pins = PIND;
  const uint8_t last = g_last_pins;
  g_count[0] += kQuadrature[((last >> 2) & 0x0Cu) | ((pins >> 4) & 0x03u)];
  g_count[1] += kQuadrature[((last >> 4) & 0x0Cu) | ((pins >> 6) & 0x03u)];
  g_last_pins = pins;
}

/* ---- the force sensor: one conversion a tick ---- */

static volatile uint16_t g_sensor;

ISR(ADC_vect) { g_sensor = ADC; }

/* ---- the servo clock ---- */

#define TIMER1_TICKS_PER_PERIOD (F_CPU / 8UL / OPENPEN_STATE_RATE_HZ)

static volatile uint32_t g_ticks;     /* servo periods since reset */
static volatile uint8_t g_tick_due;   /* set by the clock, taken by the main loop */
static volatile int32_t g_sample_count[2];
static volatile uint16_t g_sample_sensor;
static volatile uint32_t g_sample_time_us;

ISR(TIMER1_COMPA_vect) {
  g_sample_count[0] = g_count[0];
  g_sample_count[1] = g_count[1];
  g_sample_sensor = g_sensor;
  g_sample_time_us = g_ticks * (1000000UL / OPENPEN_STATE_RATE_HZ);
  ++g_ticks;
  g_tick_due = 1;
  ADCSRA |= _BV(ADSC);
}

/* ---- the UART: interrupt-driven, a receive ring and one frame in flight ---- */

#define RX_RING 128u
static volatile uint8_t g_rx[RX_RING];
static volatile uint8_t g_rx_head, g_rx_tail;

static uint8_t g_tx[HPEN_MAX_FRAME_BYTES];
static volatile uint8_t g_tx_length, g_tx_next;

ISR(USART_RX_vect) {
  const uint8_t byte = UDR0;
  const uint8_t next = (uint8_t)((g_rx_head + 1u) % RX_RING);
  if (next != g_rx_tail) {
    g_rx[g_rx_head] = byte;
    g_rx_head = next;
  }
}

ISR(USART_UDRE_vect) {
  UDR0 = g_tx[g_tx_next++];
  if (g_tx_next == g_tx_length) {
    UCSR0B &= (uint8_t)~_BV(UDRIE0);
    g_tx_length = 0;
  }
}

static uint8_t txBusy(void) { return g_tx_length != 0; }

/* Sends a frame unless one is still going out; returns whether it was sent. */
static uint8_t sendFrame(uint8_t type, const uint8_t* payload, uint8_t n) {
  if (txBusy()) return 0;
  const uint8_t length = hpen_frame(g_tx, HPEN_PROTOCOL_VERSION, type, payload, n);
  g_tx_next = 0;
  g_tx_length = length;
  __asm__ __volatile__("" ::: "memory"); /* the frame is in g_tx before the interrupt may send it */
  UCSR0B |= _BV(UDRIE0);
  return 1;
}

static int16_t takeByte(void) {
  if (g_rx_tail == g_rx_head) return -1;
  const uint8_t byte = g_rx[g_rx_tail];
  g_rx_tail = (uint8_t)((g_rx_tail + 1u) % RX_RING);
  return byte;
}

/* ---- the motors ---- */

static void motorsOff(void) {
  PORTD &= (uint8_t)~_BV(PD2);
  OCR2A = 0;
  OCR2B = 0;
  PORTB &= (uint8_t)~(_BV(PB0) | _BV(PB1) | _BV(PB2) | _BV(PB4));
}

/* Duty 0..255 for an effort's magnitude, rounded. */
static uint8_t duty(int16_t effort) {
  const int32_t magnitude = effort < 0 ? -(int32_t)effort : effort;
  const int32_t scaled = (magnitude * 255L + HPEN_EFFORT_FULL / 2) / HPEN_EFFORT_FULL;
  return (uint8_t)(scaled > 255 ? 255 : scaled);
}

static void drive(int16_t effort0, int16_t effort1) {
  uint8_t port = PORTB & (uint8_t)~(_BV(PB0) | _BV(PB1) | _BV(PB2) | _BV(PB4));
  if (effort0 > 0) port |= _BV(PB0);
  if (effort0 < 0) port |= _BV(PB1);
  if (effort1 > 0) port |= _BV(PB2);
  if (effort1 < 0) port |= _BV(PB4);
  PORTB = port;
  OCR2A = duty(effort0);
  OCR2B = duty(effort1);
  PORTD |= _BV(PD2);
}

/* ---- the protocol's state ---- */

static uint8_t g_homed;            /* the encoders were zeroed at the home pose since reset */
static uint8_t g_streaming;
static uint8_t g_motors_on;
static uint8_t g_watchdog_tripped;
static uint16_t g_state_seq;        /* the seq of the last STATE sent */
static uint8_t g_have_command;      /* a COMMAND was accepted since START */
static uint16_t g_command_seq;      /* the seq the last accepted COMMAND answered */
static uint32_t g_last_command_tick;
static struct hpen_state g_counters; /* the rx_* counters, watchdog_trips, tx_skipped */

static void sendIdentity(uint32_t nonce) {
  struct hpen_identity id;
  memset(&id, 0, sizeof id);
  id.nonce = nonce;
  id.firmware_build = OPENPEN_FIRMWARE_BUILD;
  strncpy(id.model, OPENPEN_MODEL, HPEN_MODEL_BYTES);
  id.state_rate_hz = OPENPEN_STATE_RATE_HZ;
  id.watchdog_ms = OPENPEN_WATCHDOG_MS;
  id.base_separation_m = OPENPEN_BASE_SEPARATION_M;
  id.proximal_m = OPENPEN_PROXIMAL_M;
  id.distal_m = OPENPEN_DISTAL_M;
  id.home_q0_rad = OPENPEN_HOME_Q0_RAD;
  id.home_q1_rad = OPENPEN_HOME_Q1_RAD;
  id.counts_per_joint_rev = OPENPEN_COUNTS_PER_JOINT_REV;
  id.peak_torque_Nm = OPENPEN_PEAK_TORQUE_NM;
  id.continuous_torque_Nm = OPENPEN_CONTINUOUS_TORQUE_NM;
  id.sensor_N_per_count = OPENPEN_SENSOR_N_PER_COUNT;
  id.sensor_zero_count = OPENPEN_SENSOR_ZERO_COUNT;
  id.sensor_max_count = OPENPEN_SENSOR_MAX_COUNT;
  id.motor_sign = OPENPEN_MOTOR_SIGN;
  id.status = g_homed ? HPEN_IDENTITY_HOMED : 0u;
  uint8_t payload[HPEN_IDENTITY_BYTES];
  hpen_encode_identity(payload, &id);
  /* An IDENTITY is never skipped: wait for the frame in flight. */
  while (txBusy()) {
  }
  sendFrame(HPEN_IDENTITY, payload, HPEN_IDENTITY_BYTES);
}

static void start(uint8_t flags) {
  if (flags & HPEN_START_ZERO_ENCODERS) {
    cli();
    g_count[0] = 0;
    g_count[1] = 0;
    sei();
    g_homed = 1;
  }
  motorsOff();
  g_motors_on = 0;
  g_watchdog_tripped = 0;
  g_have_command = 0;
  g_streaming = 1;
  cli();
  g_last_command_tick = g_ticks;
  sei();
}

static void stop(void) {
  motorsOff();
  g_motors_on = 0;
  g_streaming = 0;
}

/* A COMMAND answers the last STATE or the one before, and comes after the last one accepted. */
static uint8_t inSequence(uint16_t seq) {
  const uint16_t behind = (uint16_t)(g_state_seq - seq);
  if (!g_streaming || behind > 1u) return 0;
  return !g_have_command || (int16_t)(seq - g_command_seq) > 0;
}

static void command(const struct hpen_command* c) {
  if (!inSequence(c->seq)) {
    ++g_counters.rx_out_of_sequence;
    return;
  }
  g_have_command = 1;
  g_command_seq = c->seq;
  cli();
  g_last_command_tick = g_ticks;
  sei();
  g_watchdog_tripped = 0;
  g_motors_on = (c->flags & HPEN_COMMAND_ENABLE) != 0;
  if (g_motors_on) drive(c->effort0, c->effort1);
  else motorsOff();
}

/* One frame of our version from the host. */
static void frame(const struct hpen_parser* parser) {
  const uint8_t* payload = hpen_parser_payload(parser);
  switch (hpen_parser_type(parser)) {
    case HPEN_HELLO: {
      struct hpen_hello hello;
      hpen_decode_hello(payload, &hello);
      stop();
      sendIdentity(hello.nonce);
      break;
    }
    case HPEN_START: {
      struct hpen_start s;
      hpen_decode_start(payload, &s);
      start(s.flags);
      break;
    }
    case HPEN_COMMAND: {
      struct hpen_command c;
      hpen_decode_command(payload, &c);
      command(&c);
      break;
    }
    case HPEN_STOP: stop(); break;
    default: ++g_counters.rx_malformed; break; /* a device-to-host type sent to the device */
  }
}

static void receive(struct hpen_parser* parser) {
  int16_t byte;
  while ((byte = takeByte()) >= 0) {
    switch (hpen_parser_feed(parser, (uint8_t)byte)) {
      case HPEN_FRAME: frame(parser); break;
      case HPEN_BAD_CRC:
      case HPEN_BAD_LENGTH: ++g_counters.rx_malformed; break;
      case HPEN_WRONG_VERSION:
        ++g_counters.rx_wrong_version;
        /* A HELLO of another version still learns ours, so the host can name both. */
        if (hpen_parser_type(parser) == HPEN_HELLO) {
          struct hpen_hello hello;
          hpen_decode_hello(hpen_parser_payload(parser), &hello);
          stop();
          sendIdentity(hello.nonce);
        }
        break;
      case HPEN_NONE: break;
    }
  }
}

/* The tick's work in the main loop: the watchdog, then the STATE. */
static void tick(void) {
  cli();
  const uint32_t ticks = g_ticks;
  const uint32_t since_command = ticks - g_last_command_tick;
  struct hpen_state s = g_counters;
  s.count0 = g_sample_count[0];
  s.count1 = g_sample_count[1];
  s.sensor = g_sample_sensor;
  s.time_us = g_sample_time_us;
  sei();

  const uint32_t watchdog_ticks = (uint32_t)OPENPEN_WATCHDOG_MS * OPENPEN_STATE_RATE_HZ / 1000u;
  if (g_streaming && !g_watchdog_tripped && since_command >= watchdog_ticks) {
    motorsOff();
    g_motors_on = 0;
    g_watchdog_tripped = 1;
    ++g_counters.watchdog_trips;
    s.watchdog_trips = g_counters.watchdog_trips;
  }
  if (!g_streaming) return;

  s.seq = (uint16_t)(g_state_seq + 1u);
  s.flags = (uint8_t)((g_motors_on ? HPEN_STATE_MOTORS_ON : 0u) | (g_watchdog_tripped ? HPEN_STATE_WATCHDOG : 0u) |
                      ((PINC & _BV(PC1)) ? 0u : HPEN_STATE_BUTTON));
  uint8_t payload[HPEN_STATE_BYTES];
  hpen_encode_state(payload, &s);
  if (sendFrame(HPEN_STATE, payload, HPEN_STATE_BYTES)) g_state_seq = s.seq;
  else ++g_counters.tx_skipped;
}

/* ---- set-up ---- */

static void setUp(void) {
  /* Motors: direction pins and STBY out and low, PWM pins out; Timer2 fast PWM, no prescaler
   * (62.5 kHz, above hearing), non-inverting on OC2A and OC2B. */
  TCCR2A = _BV(COM2A1) | _BV(COM2B1) | _BV(WGM21) | _BV(WGM20);
  TCCR2B = _BV(CS20);
  DDRB |= _BV(PB0) | _BV(PB1) | _BV(PB2) | _BV(PB3) | _BV(PB4);
  DDRD |= _BV(PD2) | _BV(PD3);
  motorsOff();

  /* Encoders: inputs with pull-ups, pin-change interrupts on PD4..PD7. */
  DDRD &= (uint8_t)~(_BV(PD4) | _BV(PD5) | _BV(PD6) | _BV(PD7));
  PORTD |= _BV(PD4) | _BV(PD5) | _BV(PD6) | _BV(PD7);
  g_last_pins = PIND;
  PCMSK2 = _BV(PCINT20) | _BV(PCINT21) | _BV(PCINT22) | _BV(PCINT23);
  PCICR = _BV(PCIE2);

  /* Button with pull-up; the sensor on ADC0 against AVCC, 125 kHz ADC clock, interrupt on done. */
  PORTC |= _BV(PC1);
  ADMUX = _BV(REFS0);
  ADCSRA = _BV(ADEN) | _BV(ADIE) | _BV(ADPS2) | _BV(ADPS1) | _BV(ADPS0);

  /* UART: 1 Mbaud at 16 MHz is exact with U2X (UBRR = 1); 8N1. UBRR0H before UBRR0L. */
  UCSR0A = _BV(U2X0);
  UBRR0H = 0;
  UBRR0L = (uint8_t)(F_CPU / 8UL / OPENPEN_BAUD - 1UL);
  UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
  UCSR0B = _BV(RXEN0) | _BV(TXEN0) | _BV(RXCIE0);

  /* The servo clock: Timer1 CTC, prescaler 8. */
  TCCR1A = 0;
  TCCR1B = _BV(WGM12) | _BV(CS11);
  OCR1A = (uint16_t)(TIMER1_TICKS_PER_PERIOD - 1UL);
  TIMSK1 = _BV(OCIE1A);
}

int main(void) {
  wdt_enable(WDTO_60MS);
  setUp();
  sei();
  struct hpen_parser parser;
  hpen_parser_reset(&parser);
  SMCR = (uint8_t)((SMCR & (uint8_t)~(_BV(SM0) | _BV(SM1) | _BV(SM2))) | SLEEP_MODE_IDLE);
  for (;;) {
    wdt_reset();
    receive(&parser);
    if (g_tick_due) {
      g_tick_due = 0;
      tick();
    }
    /* Idle until the next interrupt when nothing is waiting (sei then sleep: no wake-up is lost). */
    cli();
    if (!g_tick_due && g_rx_tail == g_rx_head) {
      sleep_enable();
      sei();
      sleep_cpu();
      sleep_disable();
    }
    sei();
  }
}
