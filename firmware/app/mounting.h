/*
 * mounting.h - the IMU's configured mounting in the vehicle: any rotation (a 90-degree
 * turn, upside down, tilted), applied to every IMU sample before navigation, so that the
 * navigator, the odometer rows and the outputs see the vehicle's axes (x right, y forward,
 * z up). The filter estimates only the small residual on top (mounting yaw and pitch,
 * ekf.h).
 *
 * The angles are the IMU's attitude relative to the vehicle, in the navigation attitude's
 * own convention (docs/frames.md, 3-1-2): C_vi = Rz(-yaw) Rx(pitch) Ry(roll) maps a vector
 * of the IMU's axes into the vehicle's; yaw clockwise (the IMU's forward axis to the
 * vehicle's right for yaw > 0), pitch the IMU's nose up, roll its right side down. An IMU
 * turned 90 deg to the right: (0, 0, 90); upside down about its forward axis: (180, 0, 0).
 * With all three angles 0 the samples pass untouched (bit for bit).
 */
#ifndef NAVECU_MOUNTING_H
#define NAVECU_MOUNTING_H

#include <stdint.h>

#include "sins.h"

typedef struct {
    mat3_t C_vi;    /* IMU axes -> vehicle axes */
    uint8_t rotate; /* 0: the identity, nothing to do */
    uint8_t yaw_axis; /* the IMU axis (0..2) nearest the vehicle's z: its gyro is the yaw's
                         (a stuck one is replaced by the car's rate, landnav_car_yaw) */
} mounting_t;

/* From roll, pitch, yaw (rad, as above). */
void mounting_init(mounting_t *m, const nav_real_t rpy_rad[3]);

/* A vector of the IMU's axes in the vehicle's (in and out may not alias). */
void mounting_to_vehicle(const mounting_t *m, const nav_real_t imu[3], nav_real_t veh[3]);

/* One IMU sample's increments, in place, into the vehicle's axes. */
void mounting_apply(const mounting_t *m, imu_inc_t *inc);

#endif /* NAVECU_MOUNTING_H */
