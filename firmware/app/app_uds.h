/*
 * app_uds.h - the application's diagnostics: the UDS server (firmware/diag/uds.h) over one
 * ISO-TP channel (firmware/diag/isotp.h) on the configured IDs (app_config_t
 * uds_request_id / uds_response_id), and the data behind its data identifiers: one DID per
 * parameter of the table (params.toml), the identification DIDs below.
 *
 * Off the navigation path: a frame on the request ID goes to ISO-TP and nowhere else (it
 * is never counted foreign or rejected); requests are served in app_poll and right after
 * their last frame; nothing here reads or changes the navigation state except an accepted
 * WriteDataByIdentifier (the configuration in RAM), a RoutineControl (0x0200..0x0204: the
 * NVM record, the calibration, the defaults in RAM, the mounting estimate adopted in RAM;
 * docs/can.md "Routines") and ECUReset
 * (the application restarted through app_start's layers). With no diagnostic traffic it sends nothing, so the output frames are those
 * of a build without it. docs/can.md, "Diagnostics (UDS)", is the tester's description.
 */
#ifndef NAVECU_APP_UDS_H
#define NAVECU_APP_UDS_H

#include <stddef.h>
#include <stdint.h>

#include "app_config.h"
#include "hal.h"
#include "isotp.h"
#include "uds.h"

/* identification DIDs (ISO 14229-1 Table C.1; 0xF1A0.. is the manufacturer's
 * identificationOptionVehicleManufacturerSpecific range) */
#define APP_UDS_DID_SERIAL 0xF18Cu     /* ECUSerialNumber */
#define APP_UDS_DID_SW_VERSION 0xF195u /* systemSupplierECUSoftwareVersionNumber */
#define APP_UDS_DID_VEHICLE 0xF1A0u    /* the build's vehicle profile name (vehicles/NAME) */
#define APP_UDS_DID_BUILD 0xF1A2u      /* the build: target, number type, compiler (below) */
/* the automatic mounting estimate, read-only, 29 bytes: MountState (1: app_mount_state_t),
 * roll, pitch, yaw (rad), sigma roll/pitch, sigma yaw (rad), excitation (m^2/s^3), each a
 * float32 big-endian, then the windows accumulated (uint32 big-endian) */
#define APP_UDS_DID_MOUNT_EST 0x0260u
#define APP_UDS_MOUNT_EST_LEN 29u
/* the NVM record loaded at boot (nvstore.h): version, source (NVSTORE_SRC_*), entries
 * loaded, entries refused, seq (4 bytes big-endian) */
#define APP_UDS_DID_NVM_STATUS 0xF1A1u
/* the commands' status (commands.h): why the last refused command was refused
 * (cmd_refusal_t), then the commands refused (CntCmdRejected; uint32 big-endian) */
#define APP_UDS_DID_CMD_STATUS 0xF1A3u

/* RoutineControl 0x31 startRoutine routine identifiers (extended session, unlocked) */
#define APP_UDS_RID_STORE_PARAMS 0x0200u       /* parameters + calibration to NVM */
#define APP_UDS_RID_ERASE_CALIBRATION 0x0201u  /* the stored and the used calibration */
#define APP_UDS_RID_RESTORE_DEFAULTS 0x0202u   /* parameters to the defaults, in RAM */
#define APP_UDS_RID_STORE_CALIBRATION 0x0203u  /* the calibration in use to NVM */
#define APP_UDS_RID_ADOPT_MOUNTING 0x0204u     /* the mounting estimate -> imu_mount_rad, in RAM */

/* the strings behind them: build defines (the HAL has no device serial: a placeholder
 * until the ECU's unique ID is read through the HAL) */
#ifndef NAVECU_SW_VERSION
#define NAVECU_SW_VERSION "navecu 0.16.0-dev"
#endif
/* The build as the compiler saw it (never stale, unlike a stamp a build script writes):
 * the target, the navigation core's number type and the compiler's version, e.g.
 * "cortex-m4f f32 gcc 12.2.1 20221205" or "host f32 gcc 12.2.0". */
#if defined(__ARM_ARCH_7EM__)
#define NAVECU_BUILD_TARGET "cortex-m4f"
#else
#define NAVECU_BUILD_TARGET "host"
#endif
#if defined(NAV_REAL_DOUBLE)
#define NAVECU_BUILD_REAL " f64"
#else
#define NAVECU_BUILD_REAL " f32"
#endif
#if defined(__clang__)
#define NAVECU_BUILD_CC " clang " __clang_version__
#elif defined(__GNUC__)
#define NAVECU_BUILD_CC " gcc " __VERSION__
#else
#define NAVECU_BUILD_CC " cc"
#endif
#define NAVECU_BUILD NAVECU_BUILD_TARGET NAVECU_BUILD_REAL NAVECU_BUILD_CC
#ifndef NAVECU_ECU_SERIAL
#define NAVECU_ECU_SERIAL "NAVECU-00000000"
#endif

/* The parameter with this DID, or APP_PARAM_N. */
app_param_id_t app_uds_param_of_did(uint16_t did);

/* A parameter's value as its DID carries it (docs/can.md: u16 big-endian, enum one byte,
 * reals as big-endian IEEE binary32, vectors three of them): written to buf if it fits
 * cap; its length. The one codec of the UDS DIDs and of the NVM record (nvstore.h). */
size_t app_uds_param_encode(const app_config_t *cfg, app_param_id_t id, uint8_t *buf,
                            size_t cap);

/* data[0..len) as parameter id's value into *cfg, its own length and range checked (the
 * rules between parameters are not: WriteDataByIdentifier checks them after this, the NVM
 * load on the whole set, nvstore_params_decode): UDS_NRC_OK; UDS_NRC_INCORRECT_LENGTH
 * (not its length); UDS_NRC_REQUEST_OUT_OF_RANGE (out of its range). *cfg is changed only
 * on UDS_NRC_OK. */
uint8_t app_uds_param_value(app_config_t *cfg, app_param_id_t id, const uint8_t *data,
                            size_t len);

/* The diagnostic channel and server with their message buffers (a request is copied out
 * of the channel to be served; the response stays put while ISO-TP sends it). */
typedef struct {
    isotp_t tp;
    uds_t srv;
    uint8_t on;                  /* the channel started (app_uds_init succeeded) */
    uint8_t reset_due;           /* ECUReset accepted: restart once the response left */
    hal_t *hal;                  /* the HAL of the request being served (its routines) */
    uint32_t pending_sent;       /* 7F SID 78 responsePending sent before an NVM write */
    uint16_t rsp_len;
    uint8_t req[ISOTP_MAX_LEN];
    uint8_t rsp[ISOTP_MAX_LEN];
} app_uds_t;

struct app; /* app.h (its typedef app_t is output.h's) */

/* Start the channel and the server on a->cfg's IDs (app_init calls it; a is otherwise
 * initialised). 0, or -1 when the channel refuses them (diagnostics then stay off). */
int app_uds_init(struct app *a);

/* A received frame: 1 if it is the diagnostic channel's (on the request ID: taken by
 * ISO-TP, a complete request served at once), else 0 (navecu's own dispatch goes on). */
int app_uds_frame(struct app *a, hal_t *hal, const hal_can_frame_t *f);

/* From app_poll: the channel's frames due, a complete request served, the server's timers
 * (S3, the security delay), an accepted ECUReset carried out once its response left. */
void app_uds_poll(struct app *a, hal_t *hal);

/* The receive list of a board's CAN filters: app_rx_ids' and the UDS request ID (written
 * if it fits max); the number of identifiers there are. */
size_t app_uds_rx_ids(const app_config_t *cfg, uint32_t *ids, size_t max);

#endif /* NAVECU_APP_UDS_H */
