/* app_uds.c - the UDS server on the application's ISO-TP channel, and its data
 * identifiers; see app_uds.h and docs/can.md ("Diagnostics (UDS)"). */
#include "app_uds.h"

#include <string.h>

#include "app.h"
#include "app_dtc.h"
#include "vehicle.h"

static int tx_frame(void *user, const hal_can_frame_t *f)
{
    return hal_can_send((hal_t *)user, f);
}

/* ISO 14229-1 responsePending (7F SID 78), sent at once before an NVM erase and write: one
 * may take longer than the P2 the ECU announces (UDS_P2_MS, 50 ms; a 16 KiB sector erase
 * of the STM32F405 takes up to about 0.5 s and stalls the CPU); the final response then
 * follows within P2* (UDS_P2_STAR_MS), suppressed or not. A single frame: it leaves before
 * the work starts, or, refused by the CAN driver (its queue full), is given up (the
 * channel keeps no pointer to p), and the final response follows the work alone. */
static void send_pending(app_t *a, uint8_t sid)
{
    hal_t *hal = a->uds.hal;
    if (hal == NULL) {
        return;
    }
    const uint8_t p[3] = {UDS_NEGATIVE, sid, UDS_NRC_RESPONSE_PENDING};
    if (isotp_send_now(&a->uds.tp, p, sizeof p, hal_time_us(hal), tx_frame, hal) == 0) {
        app_count(&a->uds.pending_sent);
        uds_pending_sent(&a->uds.srv);
    }
}

app_param_id_t app_uds_param_of_did(uint16_t did)
{
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        if (app_params[k].did == did) {
            return (app_param_id_t)k;
        }
    }
    return APP_PARAM_N;
}

static size_t value_len(app_param_type_t t)
{
    switch (t) {
    case APP_PARAM_U16:
        return 2u;
    case APP_PARAM_ENUM:
        return 1u;
    case APP_PARAM_VEC3:
        return 12u;
    default:
        return 4u;
    }
}

static void put_f32(uint8_t *p, nav_real_t x)
{
    const float f = (float)x;
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    uds_put_u32(p, u);
}

static nav_real_t get_f32(const uint8_t *p)
{
    const uint32_t u =
        ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | p[3];
    float f;
    memcpy(&f, &u, sizeof f);
    return (nav_real_t)f;
}

size_t app_uds_param_encode(const app_config_t *cfg, app_param_id_t id, uint8_t *buf,
                            size_t cap)
{
    const app_param_type_t t = app_params[id].type;
    const size_t n = value_len(t);
    if (n > cap) {
        return n;
    }
    nav_real_t v[3];
    app_param_get(cfg, id, v);
    if (t == APP_PARAM_U16) {
        const uint16_t u = (uint16_t)v[0];
        buf[0] = (uint8_t)(u >> 8);
        buf[1] = (uint8_t)u;
    } else if (t == APP_PARAM_ENUM) {
        buf[0] = (uint8_t)v[0];
    } else {
        for (size_t i = 0u; i < n / 4u; i++) {
            put_f32(&buf[4u * i], v[i]);
        }
    }
    return n;
}

uint8_t app_uds_param_value(app_config_t *cfg, app_param_id_t id, const uint8_t *data,
                            size_t len)
{
    const app_param_type_t t = app_params[id].type;
    if (len != value_len(t)) {
        return UDS_NRC_INCORRECT_LENGTH;
    }
    nav_real_t v[3] = {NAV_C(0.0), NAV_C(0.0), NAV_C(0.0)};
    if (t == APP_PARAM_U16) {
        const uint32_t u = ((uint32_t)data[0] << 8) | data[1];
        v[0] = (nav_real_t)u;
    } else if (t == APP_PARAM_ENUM) {
        v[0] = (nav_real_t)data[0];
    } else {
        for (size_t i = 0u; i < len / 4u; i++) {
            v[i] = get_f32(&data[4u * i]);
        }
    }
    return app_param_set(cfg, id, v) != 0 ? UDS_NRC_REQUEST_OUT_OF_RANGE : UDS_NRC_OK;
}

/* app_uds_param_value with the rules between parameters: a WriteDataByIdentifier's
 * (UDS_NRC_REQUEST_OUT_OF_RANGE for a rule broken; *cfg changed only on UDS_NRC_OK) */
static uint8_t param_write(app_config_t *cfg, app_param_id_t id, const uint8_t *data,
                           size_t len)
{
    app_config_t next = *cfg;
    const uint8_t nrc = app_uds_param_value(&next, id, data, len);
    if (nrc != UDS_NRC_OK) {
        return nrc;
    }
    if (!app_config_valid(&next)) {
        return UDS_NRC_REQUEST_OUT_OF_RANGE; /* a rule between parameters */
    }
    *cfg = next;
    return UDS_NRC_OK;
}

/* the string's characters without a terminator (a DID's ASCII value), if they fit; its
 * length, or cap + 1 if it is longer: the server answers 0x14 for any length > cap. Its
 * own bounded count, not strlen: this was the ECU image's only strlen, newlib-nano's
 * word-at-a-time assembly of 220 bytes of flash, for four strings of under 50 characters
 * read by a diagnostic request (and GCC makes a plain count to the terminator a call of
 * strlen again). */
static size_t put_string(uint8_t *buf, size_t cap, const char *s)
{
    size_t n = 0u;
    while (n <= cap && s[n] != '\0') {
        n++;
    }
    if (n <= cap) {
        for (size_t i = 0u; i < n; i++) {
            buf[i] = (uint8_t)s[i];
        }
    }
    return n;
}

static size_t put_mount_est(const app_t *a, uint8_t *buf, size_t cap)
{
    if (cap < APP_UDS_MOUNT_EST_LEN) {
        return APP_UDS_MOUNT_EST_LEN;
    }
    const mount_est_result_t *r = app_mount_estimate(a);
    const nav_real_t v[6] = {r->rpy_rad[0],   r->rpy_rad[1],    r->rpy_rad[2],
                             r->sigma_rp_rad, r->sigma_yaw_rad, r->excite_m2ps3};
    buf[0] = a->keep.mount_state;
    for (size_t i = 0u; i < 6u; i++) {
        put_f32(&buf[1u + 4u * i], v[i]);
    }
    for (size_t i = 0u; i < 4u; i++) {
        buf[25u + i] = (uint8_t)(r->n_windows >> (24u - 8u * i));
    }
    return APP_UDS_MOUNT_EST_LEN;
}

static size_t read_did(void *user, uint16_t did, uint8_t *buf, size_t cap)
{
    const app_t *a = (const app_t *)user;
    const char *str = NULL; /* the DIDs whose value is a string */
    if (did == APP_UDS_DID_SW_VERSION) {
        str = NAVECU_SW_VERSION;
    } else if (did == APP_UDS_DID_SERIAL) {
        str = NAVECU_ECU_SERIAL;
    } else if (did == APP_UDS_DID_VEHICLE) {
        str = vehicle_profile.name;
    } else if (did == APP_UDS_DID_BUILD) {
        str = NAVECU_BUILD;
    } else {
        /* not a string */
    }
    if (str != NULL) {
        return put_string(buf, cap, str);
    }
    if (did == APP_UDS_DID_MOUNT_EST) {
        return put_mount_est(a, buf, cap);
    }
    if (did == APP_UDS_DID_NVM_STATUS) {
        if (cap < 8u) {
            return 8u;
        }
        buf[0] = a->nvm.version;
        buf[1] = a->nvm.source;
        buf[2] = a->nvm.loaded;
        buf[3] = a->nvm.refused;
        uds_put_u32(&buf[4], a->nvm.seq);
        return 8u;
    }
    if (did == APP_UDS_DID_CMD_STATUS) {
        if (cap < 5u) {
            return 5u;
        }
        buf[0] = a->keep.cmd_refusal;
        uds_put_u32(&buf[1], a->keep.health.cmd_rejected);
        return 5u;
    }
    const app_param_id_t id = app_uds_param_of_did(did);
    if (id == APP_PARAM_N) {
        return 0u;
    }
    return app_uds_param_encode(&a->cfg, id, buf, cap);
}

static int is_writable(void *user, uint16_t did)
{
    (void)user;
    const app_param_id_t id = app_uds_param_of_did(did);
    return (id != APP_PARAM_N && !app_params[id].uds_read_only) ? 1 : 0;
}

static uint8_t write_did(void *user, uint16_t did, const uint8_t *data, size_t len)
{
    app_t *a = (app_t *)user;
    const app_param_id_t id = app_uds_param_of_did(did);
    if (id == APP_PARAM_N || app_params[id].uds_read_only) {
        return UDS_NRC_REQUEST_OUT_OF_RANGE;
    }
    if (len != value_len(app_params[id].type)) {
        return UDS_NRC_INCORRECT_LENGTH;
    }
    /* a parameter app_init copies into a module changes nothing while navigation (or
     * levelling) runs on the copy: refused until navigation is stopped (CMD_Control Reset,
     * or before the first position), then in force after ECUReset */
    if (app_params[id].at_reset && a->run.mode != APP_MODE_WAIT_INIT) {
        return UDS_NRC_CONDITIONS_NOT_CORRECT;
    }
    /* in RAM; RoutineControl StoreParameters (0x0200) saves it in NVM (docs/can.md) */
    return param_write(&a->cfg, id, data, len);
}

/* saving or erasing the NVM stalls the CPU (calstore.h): only with navigation not started
 * or the car standing */
/* the calibration in use as a record (source None: nothing calibrated) */
static cal_record_t cal_in_use(const calib_t *c)
{
    cal_record_t r = {0.0f, 0.0f, 0.0f, (uint8_t)CAL_SRC_NONE};
    if (c->source != (uint8_t)CAL_SRC_NONE) {
        r.dh_rad = (float)c->dh_rad;
        r.odo_scale_err = (float)c->mu;
        r.base_m = (float)c->base_m;
        r.source = c->source;
    }
    return r;
}

/* RestoreDefaults: every UDS-writable parameter to the table's default (the read-only
 * ones, e.g. the diagnostic IDs, stay) */
static uint8_t restore_defaults(app_t *a)
{
    const app_config_t d = app_default_config();
    app_config_t next = a->cfg;
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        if (!app_params[k].uds_read_only) {
            nav_real_t v[3];
            app_param_get(&d, (app_param_id_t)k, v);
            (void)app_param_set(&next, (app_param_id_t)k, v);
        }
    }
    if (!app_config_valid(&next)) {
        return UDS_NRC_CONDITIONS_NOT_CORRECT;
    }
    a->cfg = next;
    return UDS_NRC_OK;
}

/* ---- the fault memory (app_dtc.h): 0x19, 0x14 ---- */

static size_t uds_dtc_count(void *user)
{
    (void)user;
    return (size_t)DTC_N;
}

static int uds_dtc_get(void *user, size_t index, uint32_t *dtc, uint8_t *status)
{
    const app_t *a = (const app_t *)user;
    if (index >= (size_t)DTC_N) {
        return -1;
    }
    *dtc = dtc_table[index].number;
    *status = dtc_status(&a->keep.dtc, index);
    return 0;
}

static uint8_t uds_dtc_clear(void *user, uint32_t group)
{
    app_t *a = (app_t *)user;
    (void)group; /* the server passes all groups only */
    if (app_nvm_write_allowed(a)) {
        send_pending(a, UDS_SID_CLEAR_DTC); /* the status bytes' NVM write follows */
    }
    return app_dtc_clear(a, a->uds.hal); /* the HAL of this request (serve) */
}

static uint8_t uds_dtc_availability(void *user)
{
    (void)user;
    return (uint8_t)DTC_AVAILABILITY_MASK;
}

static int has_routine(void *user, uint16_t rid)
{
    (void)user;
    return rid >= APP_UDS_RID_STORE_PARAMS && rid <= APP_UDS_RID_ADOPT_MOUNTING;
}

static uint8_t start_routine(void *user, uint16_t rid, const uint8_t *data, size_t len)
{
    app_t *a = (app_t *)user;
    hal_t *hal = a->uds.hal;
    calib_t *c = &a->keep.cal;
    (void)data; /* rid is one of has_routine's */
    if (len != 0u) {
        return UDS_NRC_INCORRECT_LENGTH; /* no option record */
    }
    if (rid == APP_UDS_RID_RESTORE_DEFAULTS) {
        /* at_reset parameters among them: navigation not started (as a write) */
        return a->run.mode == APP_MODE_WAIT_INIT ? restore_defaults(a)
                                                 : UDS_NRC_CONDITIONS_NOT_CORRECT;
    }
    if (rid == APP_UDS_RID_ADOPT_MOUNTING) {
        /* in RAM, as RestoreDefaults (0x0200 saves it); no converged estimate: 0x22 */
        return app_adopt_mounting(a) == 0 ? UDS_NRC_OK : UDS_NRC_CONDITIONS_NOT_CORRECT;
    }
    if (!app_nvm_write_allowed(a) || hal == NULL) {
        return UDS_NRC_CONDITIONS_NOT_CORRECT;
    }
    if (rid == APP_UDS_RID_STORE_PARAMS) {
        send_pending(a, UDS_SID_ROUTINE);
        const cal_record_t r = cal_in_use(c);
        if (nvstore_save(hal, &c->store, &a->cfg, &r) != 0) {
            c->nvm_error = 1u;
            return UDS_NRC_GENERAL_PROGRAMMING_FAILURE;
        }
        c->nvm_error = 0u;
        c->stored = r.source != (uint8_t)CAL_SRC_NONE ? 1u : 0u;
        return UDS_NRC_OK;
    }
    if (rid == APP_UDS_RID_ERASE_CALIBRATION) {
        send_pending(a, UDS_SID_ROUTINE);
        calib_erase(c, hal, a->run.mode == APP_MODE_NAVIGATING ? &a->run.dr : NULL);
        return c->nvm_error ? UDS_NRC_GENERAL_PROGRAMMING_FAILURE : UDS_NRC_OK;
    }
    /* StoreCalibration: the values in use */
    if (c->source == (uint8_t)CAL_SRC_NONE) {
        return UDS_NRC_CONDITIONS_NOT_CORRECT; /* nothing calibrated */
    }
    send_pending(a, UDS_SID_ROUTINE);
    calib_store(c, &a->run.cal, hal, a->keep.n_samples);
    return c->nvm_error ? UDS_NRC_GENERAL_PROGRAMMING_FAILURE : UDS_NRC_OK;
}

/* 0x10: the default and extended sessions as the server has them; the programming
 * session is the bootloader's (issue #19): 7F 10 78 now, the request left for it and the
 * MCU reset (hal_bootloader does not return); the bootloader sends the 50 02. A board
 * without a bootloader (the host, QEMU): 0x22. */
static uint8_t session_change(void *user, uint8_t session)
{
    app_t *a = (app_t *)user;
    if (session != UDS_SESSION_PROGRAMMING) {
        return UDS_NRC_OK;
    }
    hal_t *hal = a->uds.hal;
    /* not during the security delay: the bootloader starts with a fresh count, and would
     * give three more keys at once */
    if (hal == NULL || a->uds.srv.delay_on || hal_bootloader(hal, 0) != 0) {
        return UDS_NRC_CONDITIONS_NOT_CORRECT;
    }
    send_pending(a, UDS_SID_SESSION);
    app_dtc_flush(a, hal); /* the bytes held for a standstill, before the reset */
    (void)hal_bootloader(hal, 1);
    return UDS_NRC_CONDITIONS_NOT_CORRECT; /* it returned: the board could not reset */
}

int app_uds_init(app_t *a)
{
    isotp_config_t c;
    isotp_config_defaults(&c, a->cfg.uds_request_id, a->cfg.uds_response_id);
    const uds_if_t itf = {
        .user = a,
        .read_did = read_did,
        .write_did = write_did,
        .is_writable = is_writable,
        .dtc_count = uds_dtc_count,
        .dtc_get = uds_dtc_get,
        .dtc_clear = uds_dtc_clear,
        .dtc_availability = uds_dtc_availability,
        .start_routine = start_routine,
        .has_routine = has_routine,
        .session_change = session_change,
    };
    a->uds.on = 0u;
    if (isotp_init(&a->uds.tp, &c) != 0 || uds_init(&a->uds.srv, &itf, 0u) != 0) {
        return -1;
    }
    a->uds.on = 1u;
    return 0;
}

/* ECUReset hardReset: the application restarted as its board started it (app_start's
 * layers again); one started by app_init alone keeps its configuration in RAM */
static void ecu_restart(app_t *a, hal_t *hal)
{
    app_dtc_flush(a, hal);
    const app_config_t cfg = a->cfg;
    const uint8_t started = a->started;
    if (started && app_start(a, hal) == NAV_OK) {
        return;
    }
    if (app_init(a, &cfg) == NAV_OK) {
        a->started = started;
        app_boot(a, hal);
    }
}

static void serve(app_t *a, hal_t *hal, uint64_t now)
{
    app_uds_t *u = &a->uds;
    u->hal = hal; /* the routines' NVM */
    (void)isotp_poll(&u->tp, now, tx_frame, hal);
    if (isotp_tx_busy(&u->tp)) {
        return; /* the response buffer is in use; a new request waits in the channel */
    }
    if (u->reset_due) {
        u->reset_due = 0u;
        ecu_restart(a, hal); /* the response went out (or its transmission ended) */
        return;
    }
    size_t len = 0u;
    if (isotp_receive(&u->tp, u->req, sizeof u->req, &len) != 0) {
        return;
    }
    const size_t n = uds_handle(&u->srv, u->req, len, now, u->rsp, sizeof u->rsp);
    if (uds_take_reset(&u->srv)) {
        u->reset_due = 1u;
    }
    int sent = 0;
    if (n > 0u && isotp_send(&u->tp, u->rsp, n, now) == 0) {
        sent = 1;
    }
    if (sent) {
        (void)isotp_poll(&u->tp, now, tx_frame, hal);
    } else {
        if (u->reset_due) {
            u->reset_due = 0u;
            ecu_restart(a, hal); /* suppressed response: at once */
        }
    }
}

int app_uds_frame(app_t *a, hal_t *hal, const hal_can_frame_t *f)
{
    if (!a->uds.on || f->extended || f->id != a->uds.tp.cfg.rx_id) {
        return 0;
    }
    const uint64_t now = hal_time_us(hal);
    (void)isotp_on_frame(&a->uds.tp, f, now);
    serve(a, hal, now);
    return 1;
}

void app_uds_poll(app_t *a, hal_t *hal)
{
    if (!a->uds.on) {
        return;
    }
    const uint64_t now = hal_time_us(hal);
    serve(a, hal, now);
    if (a->uds.on) {
        uds_poll(&a->uds.srv, now);
    }
}

size_t app_uds_rx_ids(const app_config_t *cfg, uint32_t *ids, size_t max)
{
    const size_t n = app_rx_ids(cfg->can_ids, ids, max);
    if (n < max) {
        ids[n] = cfg->uds_request_id;
    }
    return n + 1u;
}
