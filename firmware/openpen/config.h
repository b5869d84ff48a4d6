#ifndef OPENPEN_CONFIG_H
#define OPENPEN_CONFIG_H
/* The reference open pen's build constants (docs/hardware.md, "Bill of materials"): a lab that
 * builds other links, motors or a sensor edits this file and rebuilds. hattr reads every one of
 * them from the IDENTITY packet, so nothing on the host side changes. */

#define OPENPEN_FIRMWARE_BUILD 1
#define OPENPEN_MODEL "openpen-5bar"

/* The servo clock and the link. */
#define OPENPEN_STATE_RATE_HZ 1000u
#define OPENPEN_WATCHDOG_MS 20u
#define OPENPEN_BAUD 1000000UL

/* The five-bar: motors 40 mm apart, proximal links 80 mm, distal links 100 mm. At the home pose
 * (both proximal links against their stops, 45 degrees out from vertical) the pen sits 121 mm in
 * front of the base line, on its middle. */
#define OPENPEN_BASE_SEPARATION_M 0.040f
#define OPENPEN_PROXIMAL_M 0.080f
#define OPENPEN_DISTAL_M 0.100f
#define OPENPEN_HOME_Q0_RAD 2.35619449f /* 135 degrees */
#define OPENPEN_HOME_Q1_RAD 0.78539816f /* 45 degrees */

/* 500-line encoders decoded x4 on the motor shaft, a 10:1 capstan to the joint. */
#define OPENPEN_COUNTS_PER_JOINT_REV 20000UL

/* 12 V through a TB6612FNG into a 4 ohm motor with 23.1 mNm/A: 3 A at full duty is the peak,
 * 1.2 A (the driver's continuous rating) the continuous torque; both through the 10:1 capstan. */
#define OPENPEN_PEAK_TORQUE_NM 0.693f
#define OPENPEN_CONTINUOUS_TORQUE_NM 0.277f
/* Bit i set: motor i's positive effort turns its joint clockwise (wiring). */
#define OPENPEN_MOTOR_SIGN 0x00u

/* A 1 kg beam load cell behind an INA125 amplifier: 0.5 V at no load, 10 N over 4.5 V, read by
 * the 10-bit ADC against AVCC (5 V). */
#define OPENPEN_SENSOR_N_PER_COUNT 0.010851f
#define OPENPEN_SENSOR_ZERO_COUNT 102u
#define OPENPEN_SENSOR_MAX_COUNT 1023u

#endif
