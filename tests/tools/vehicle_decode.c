/*
 * vehicle_decode.c - one vehicle profile's generated layer (firmware/vehicle/vehicle.h,
 * build/vehicle/NAME/) as a filter, for tests/python/test_vehicle_profiles.py, which checks
 * it against cantools. Built once per profile: build/host/tests/vehicle_decode-NAME.
 *
 *     vehicle_decode < frames.log    one output line per input line (candump lines,
 *                                    hal/common/candump.h):
 *         VERDICT KIND FL FR RL RR GEAR YAW
 *       vehicle_decode()'s verdict (OK, BAD_DLC, BAD_CHECKSUM, BAD_VALUE, BAD_COUNTER; HELD
 *       for one axle's half of split wheel speeds, VEHICLE_WHEELS_HELD) and
 *       the message kind (NONE, WHEELS, GEAR, YAW_RATE), their names in vehicle.h without
 *       the prefix;
 *       the wheel speeds in m/s, the gear direction (-1, 0, +1) and the yaw rate in rad/s,
 *       0 where the message does not set them; every value as %.9g, which identifies a
 *       float exactly. A line candump_parse_line does not take as a frame: MALFORMED.
 *       The frames go through one receive state, in order, as the firmware's (rx_state_t):
 *       a rolling counter is checked against the previous frame of its message.
 *     vehicle_decode --profile       the profile's name and the car identifiers it reads
 *                                    (vehicle_rx_ids), hexadecimal, on one line
 * Exit status 0, or 2 on a usage error.
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "candump.h"
#include "vehicle.h"

static const char *verdict_name(vehicle_verdict_t v)
{
    switch (v) {
    case VEHICLE_OK:
        return "OK";
    case VEHICLE_BAD_DLC:
        return "BAD_DLC";
    case VEHICLE_BAD_CHECKSUM:
        return "BAD_CHECKSUM";
    case VEHICLE_BAD_VALUE:
        return "BAD_VALUE";
    case VEHICLE_BAD_COUNTER:
        return "BAD_COUNTER";
    case VEHICLE_WHEELS_HELD:
        return "HELD";
    default:
        return "UNKNOWN_VERDICT";
    }
}

static const char *kind_name(vehicle_kind_t k)
{
    switch (k) {
    case VEHICLE_MSG_NONE:
        return "NONE";
    case VEHICLE_MSG_WHEELS:
        return "WHEELS";
    case VEHICLE_MSG_GEAR:
        return "GEAR";
    case VEHICLE_MSG_YAW_RATE:
        return "YAW_RATE";
    default:
        return "UNKNOWN_KIND";
    }
}

static int print_profile(void)
{
    uint32_t ids[16];
    const size_t n = vehicle_rx_ids(ids, sizeof ids / sizeof ids[0]);
    printf("%s", vehicle_profile.name);
    for (size_t i = 0u; i < n && i < sizeof ids / sizeof ids[0]; i++) {
        printf(" 0x%03X", (unsigned)ids[i]);
    }
    printf("\n");
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "--profile") == 0) {
        return print_profile();
    }
    if (argc != 1) {
        fprintf(stderr, "usage: %s [--profile] < candump.log\n", argv[0]);
        return 2;
    }
    char line[256];
    vehicle_counters_t counters;
    memset(&counters, 0, sizeof counters);
    while (fgets(line, sizeof line, stdin) != NULL) {
        const size_t n = strcspn(line, "\r\n");
        hal_can_frame_t f;
        if (candump_parse_line(line, n, &f) != CANDUMP_FRAME) {
            printf("MALFORMED\n");
            continue;
        }
        vehicle_msg_t m;
        memset(&m, 0, sizeof m);
        const vehicle_verdict_t v = vehicle_decode(&f, &counters, &m);
        printf("%s %s %.9g %.9g %.9g %.9g %d %.9g\n", verdict_name(v), kind_name(m.kind),
               (double)m.wheel_mps[0], (double)m.wheel_mps[1], (double)m.wheel_mps[2],
               (double)m.wheel_mps[3], (int)m.gear_direction, (double)m.yaw_rate_rps);
    }
    return 0;
}
