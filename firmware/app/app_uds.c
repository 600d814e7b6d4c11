/* app_uds.c - the UDS server on the application's ISO-TP channel, and its data
 * identifiers; see app_uds.h and docs/can.md ("Diagnostics (UDS)"). */
#include "app_uds.h"

#include <string.h>

#include "app.h"
#include "vehicle.h"

static int tx_frame(void *user, const hal_can_frame_t *f)
{
    return hal_can_send((hal_t *)user, f);
}

/* the parameter with this DID, or APP_PARAM_N */
static app_param_id_t param_of_did(uint16_t did)
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
    p[0] = (uint8_t)(u >> 24);
    p[1] = (uint8_t)(u >> 16);
    p[2] = (uint8_t)(u >> 8);
    p[3] = (uint8_t)u;
}

static nav_real_t get_f32(const uint8_t *p)
{
    const uint32_t u =
        ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | p[3];
    float f;
    memcpy(&f, &u, sizeof f);
    return (nav_real_t)f;
}

/* the string's characters without a terminator (a DID's ASCII value) */
static size_t put_string(uint8_t *buf, size_t cap, const char *s)
{
    const size_t n = strlen(s);
    if (n <= cap) {
        for (size_t i = 0u; i < n; i++) {
            buf[i] = (uint8_t)s[i];
        }
    }
    return n; /* > cap: the server answers 0x14 */
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
    if (did == APP_UDS_DID_SW_VERSION) {
        return put_string(buf, cap, NAVECU_SW_VERSION);
    }
    if (did == APP_UDS_DID_SERIAL) {
        return put_string(buf, cap, NAVECU_ECU_SERIAL);
    }
    if (did == APP_UDS_DID_VEHICLE) {
        return put_string(buf, cap, vehicle_profile.name);
    }
    if (did == APP_UDS_DID_MOUNT_EST) {
        return put_mount_est(a, buf, cap);
    }
    const app_param_id_t id = param_of_did(did);
    if (id == APP_PARAM_N) {
        return 0u;
    }
    const app_param_type_t t = app_params[id].type;
    const size_t n = value_len(t);
    if (n > cap) {
        return n;
    }
    nav_real_t v[3];
    app_param_get(&a->cfg, id, v);
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

static int is_writable(void *user, uint16_t did)
{
    (void)user;
    const app_param_id_t id = param_of_did(did);
    return (id != APP_PARAM_N && !app_params[id].uds_read_only) ? 1 : 0;
}

static uint8_t write_did(void *user, uint16_t did, const uint8_t *data, size_t len)
{
    app_t *a = (app_t *)user;
    const app_param_id_t id = param_of_did(did);
    if (id == APP_PARAM_N || app_params[id].uds_read_only) {
        return UDS_NRC_REQUEST_OUT_OF_RANGE;
    }
    const app_param_type_t t = app_params[id].type;
    if (len != value_len(t)) {
        return UDS_NRC_INCORRECT_LENGTH;
    }
    /* a parameter app_init copies into a module changes nothing while navigation (or
     * levelling) runs on the copy: refused until navigation is stopped (CMD_Control Reset,
     * or before the first position), then in force after ECUReset */
    if (app_params[id].at_reset && a->run.mode != APP_MODE_WAIT_INIT) {
        return UDS_NRC_CONDITIONS_NOT_CORRECT;
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
    app_config_t next = a->cfg;
    if (app_param_set(&next, id, v) != 0 || !app_config_valid(&next)) {
        return UDS_NRC_REQUEST_OUT_OF_RANGE; /* its range, or a rule between parameters */
    }
    a->cfg = next; /* in RAM: not persisted in NVM (docs/can.md) */
    return UDS_NRC_OK;
}

int app_uds_init(app_t *a)
{
    isotp_config_t c;
    isotp_config_defaults(&c, a->cfg.uds_request_id, a->cfg.uds_response_id);
    const uds_if_t itf = {a, read_did, write_did, is_writable};
    a->uds.on = 0u;
    if (isotp_init(&a->uds.tp, &c) != 0 || uds_init(&a->uds.srv, &itf, 0u) != 0) {
        return -1;
    }
    a->uds.on = 1u;
    return 0;
}

/* the application restarted with its configuration as it is now (ECUReset hardReset) */
static void ecu_restart(app_t *a, hal_t *hal)
{
    const app_config_t cfg = a->cfg;
    if (app_init(a, &cfg) == NAV_OK) {
        app_boot(a, hal);
    }
}

static void serve(app_t *a, hal_t *hal, uint64_t now)
{
    app_uds_t *u = &a->uds;
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
