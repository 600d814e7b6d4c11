/*
 * imu_stream.h - the IMU sample stream: IMU_Rate and IMU_Accel paired into one sample
 * (one E2E data element over two frames, docs/can.md), its alive counter with
 * resynchronisation after a corrupt counter, lost samples found by the counter (and, for
 * gaps of a whole counter cycle, by receive time), the samples to bridge a short gap by
 * interpolation, and plausibility: an axis at its configured range (saturated) or
 * repeating its raw value while the car moves (stuck).
 *
 * Samples stay in the protocol's raw units (int32 LSB): interpolation and the checks are
 * integer arithmetic, the same on every target. app_rx_imu_increment turns them into SI.
 */
#ifndef NAVECU_IMU_STREAM_H
#define NAVECU_IMU_STREAM_H

#include <stdint.h>

#include "app_rx.h"
#include "e2e.h"

/* What survives a navigation reset: the counter (a replayed sample is never new), the
 * time of the last sample (staleness), the IMU's fault bit, and the saturation limits. */
typedef struct {
    e2e_counter_t counter;
    uint8_t have_sample;   /* a sample has been taken since boot */
    uint64_t last_t_us;    /* HAL time of the last sample (staleness, time gaps) */
    uint8_t fault;         /* the last sample's ImuFault bit */
    int32_t sat_raw[2];    /* gyro and accelerometer range in raw LSB per sample */
    int32_t stuck_raw[2];  /* a stuck axis's 1 sigma per sample: a car's motion, at most
                              the range (APP_STUCK_RATE_RPS, APP_STUCK_ACCEL_MPS2) */
    uint32_t noise_lsb[2]; /* gyro and accelerometer noise shown (APP_IMU_NOISE_MIN_LSB) */
    uint32_t rate_hz;      /* the configured IMU rate */
    uint32_t accel_id;     /* IMU_Accel's CAN identifier: the pair CRC covers it */
    /* imu_time = stamped: each sample's interval from the IMU's own IMU_Time stamps */
    uint8_t stamped;       /* the stamps give the time (imu_link_stamped) */
    uint8_t have_stamp;    /* stamp_us anchors the next sample's interval */
    uint8_t stamp_refused; /* samples refused for their stamp in a row */
    uint32_t stamp_us;     /* the last sample's IMU_Time (us, wrapping at 2^32) */
} imu_link_t;

/* Plausibility state: per axis (angle x y z, velocity x y z) the repeats of the raw value
 * and its noise (|second difference| sums) over the current and the previous half-window
 * block. */
typedef struct {
    int32_t last_raw[6];
    uint32_t same_n[6];
    int32_t last2_raw[6];            /* the raw value before last_raw */
    uint32_t blk_jit[6], prev_jit[6]; /* sums of |second difference| over the blocks */
    uint32_t blk_n, prev_n;
    uint8_t hist;                    /* samples seen, up to 2 (the second difference) */
    uint8_t stuck_seen; /* axes whose current stuck episode was counted (bits) */
} imu_plaus_t;

/* An IMU_Rate waiting for its IMU_Accel. */
typedef struct {
    uint8_t counter;
    uint8_t data[8];       /* its payload, covered by the pair CRC */
    int32_t raw[3];
} imu_half_t;

/* What restarts with navigation: the pair in assembly and the checks. Two IMU_Rate
 * frames may wait at once: on a shared bus another node's frame on IMU_Rate's identifier
 * must not take the place of the real one; IMU_Accel pairs with the one whose counter
 * and pair CRC match. */
#define IMU_PENDING_MAX 2u
typedef struct {
    imu_half_t pending[IMU_PENDING_MAX]; /* oldest first */
    uint8_t n_pending;
    uint8_t resync_valid;  /* samples held for a counter jump, each following the one
                              before (up to APP_IMU_JUMP_HELD): they wait for confirmation */
    uint8_t resync_counter;
    uint8_t time_valid;    /* stamped: an IMU_Time waits for its sample */
    uint8_t time_counter;  /* its ImuCounter */
    uint32_t time_us;      /* its SampleTime */
    imu_plaus_t plaus;
} imu_stream_t;

typedef enum {
    IMU_SAMPLE = 0,     /* a sample is ready (imu_sample_t) */
    IMU_REJ_PAIR,       /* imu_pair_broken: IMU_Accel without its IMU_Rate */
    IMU_REJ_CRC,        /* bad_crc: no waiting IMU_Rate gives the pair CRC (they wait on
                           for the real IMU_Accel) */
    IMU_REJ_COUNTER,    /* bad_counter: repeated, held for confirmation, or old */
    IMU_REJ_TIME,       /* stamped (imu_time): no IMU_Time of this counter, a stamp not
                           after the previous sample's, or an interval outside the band
                           (APP_IMU_TIME_BAND_*): the sample is refused and, like a lost
                           one, bridged by the next (bad_value, of it imu_timing) */
} imu_verdict_t;

/* imu_sample_t.saturated and .stuck, bit i for raw[i]: each sensor's axes */
#define IMU_AXES_GYRO 0x07u
#define IMU_AXES_ACCEL 0x38u

typedef struct {
    int32_t raw[6];      /* this sample: angle x y z, velocity x y z, LSB */
    int32_t prev_raw[6]; /* the last sample before it: where a bridge starts */
    uint64_t lost;       /* samples missing before this one */
    uint64_t lost_by_time; /* of lost, the whole counter cycles seen only in receive time */
    uint8_t time_gap;    /* some were seen missing only in receive time */
    uint8_t saturated;   /* the axes at their range (bit i: raw[i]; 0: none) */
    uint8_t stuck_new;   /* axes found stuck this sample (each counted once per episode) */
    uint8_t stuck;       /* the axes found stuck whose value still repeats (bit i: raw[i];
                            0: none) */
    uint8_t dropped;     /* IMU_Rate frames that waited before the one paired: no IMU_Accel
                            came for them (count imu_pair_broken); a newer one waits on */
    uint32_t dt_us;      /* stamped: the IMU_Time interval from the previous sample to this
                            one, over the lost + 1 samples it covers (imu_stream_dt_us); 0
                            on the grid, and for the first stamp (no interval yet: the
                            nominal period) */
    uint8_t time_reset;  /* stamped: the stamps restarted after APP_IMU_TIME_RESYNC refusals,
                            the last a stamp behind the last one taken (the clock jumped
                            back): the time since the previous sample is unknown, as after
                            a gap too long to bridge */
} imu_sample_t;

/* Boot: the saturation limits from the configured ranges (rad/s, m/s^2) and IMU rate;
 * accel_id: IMU_Accel's identifier. */
void imu_link_init(imu_link_t *l, uint32_t rate_hz, nav_real_t gyro_range_rps,
                   nav_real_t accel_range_mps2, uint32_t accel_id);

/* After imu_link_init: the gyro's angle random walk (rad/sqrt(s)), whose per-sample sigma
 * is the noise another gyro axis must show for a repeating one to be stuck. */
void imu_link_noise(imu_link_t *l, nav_real_t gyro_arw_rad_rts);

/* After imu_link_init: imu_time = stamped (1) or grid (0). */
void imu_link_stamped(imu_link_t *l, int stamped);

/* An IMU_Time (its counter checked in range, its CRC passed): the stamp of the sample of
 * this counter, held for it (a newer one replaces it). Ignored on the grid. Stamped, a
 * sample is taken only with the stamp of its own counter, and its interval is its stamp
 * less the previous sample's (u32 wrapping arithmetic: the IMU clock wraps every 71.6
 * min); lost samples between (the counter's, or whole counter cycles the stamps show,
 * as receive time does on the grid) share the interval. */
void imu_stream_time(imu_stream_t *s, const imu_link_t *l, uint8_t counter, uint32_t t_us);

/* An IMU_Rate (its counter already checked in range): held for its IMU_Accel beside the
 * one already waiting. Returns 1 if the oldest of two waiting ones had to go (it got no
 * IMU_Accel: count imu_pair_broken). */
int imu_stream_rate(imu_stream_t *s, uint8_t counter, const int32_t raw[3],
                    const uint8_t data[8]);

/* An IMU_Accel received at t_us: pair, CRC, counter, gap and plausibility. On IMU_SAMPLE,
 * *out holds the sample and l is updated. */
imu_verdict_t imu_stream_accel(imu_stream_t *s, imu_link_t *l, uint8_t counter, uint8_t fault,
                               const int32_t raw[3], const uint8_t data[8], uint64_t t_us,
                               imu_sample_t *out);

/* The k-th (0-based, k < out->lost) bridged sample of a gap: linear between prev_raw and
 * raw, rounded to nearest. */
void imu_stream_bridge(const imu_sample_t *smp, uint64_t k, int32_t w_raw[3], int32_t v_raw[3]);

/* Stamped: the interval (us) of the k-th sample of a sample's lost + 1 (k < lost: the
 * bridged ones, k = lost: the sample itself); they add up to dt_us exactly. 0 when the
 * sample has no interval (dt_us 0). */
uint32_t imu_stream_dt_us(const imu_sample_t *smp, uint64_t k);

#endif /* NAVECU_IMU_STREAM_H */
