/* app_config.c - the default configuration and its range check, both from the parameter
 * table (firmware/app/params.toml, generated app_params.c); see app_config.h. */
#include "app_config.h"

#include <string.h>

#include "vehicle.h"

app_config_t app_default_config(void)
{
    app_config_t cfg;
    app_config_defaults(&cfg);
    return cfg;
}

void app_config_defaults(app_config_t *out)
{
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        const app_param_id_t id = (app_param_id_t)k;
        const nav_real_t d = app_params[k].default_si; /* a vec3's x, y and z alike */
        const nav_real_t v[3] = {d, d, d};
        (void)app_param_set(out, id, v);
    }
    out->odo_track_m = vehicle_profile.track_m;
    out->odo_wheelbase_m = vehicle_profile.wheelbase_m;
    out->odo_step_mps = vehicle_profile.wheel_step_mps;
    for (int i = 0; i < (int)NAVECU_MSG_N; i++) {
        out->can_ids[i] = vehicle_profile.can_ids[i];
    }
}

/* x equals y (no -Wfloat-equal: neither below nor above) */
static int same(nav_real_t x, nav_real_t y)
{
    return !(x < y) && !(x > y);
}

int app_config_preset(app_config_t *cfg, app_preset_id_t id)
{
    if ((unsigned)id >= (unsigned)APP_PRESET_N) {
        return -1;
    }
    for (int k = 0; k < APP_PRESET_PARAMS; k++) {
        const nav_real_t v[3] = {app_presets[id].value_si[k], NAV_C(0.0), NAV_C(0.0)};
        if (app_param_set(cfg, app_preset_params[k], v) != 0) {
            return -1; /* cannot happen: the generator checks the presets' ranges */
        }
    }
    return 0;
}

/* A parameter's field is read and written through its offset and size in app_config_t
 * (the generated table, which checks at compile time that a u16 is 2 bytes, a real and a
 * vec3 one and three nav_real_t, an enum 1 or 4 bytes with its index as its value): one
 * loop for every parameter, where a switch of a case per parameter took 1 kB of the
 * ECU's flash. Bytes are copied, so no field is read through another type. */
void app_param_get(const app_config_t *cfg, app_param_id_t id, nav_real_t v[3])
{
    v[0] = NAV_C(0.0);
    v[1] = NAV_C(0.0);
    v[2] = NAV_C(0.0);
    if ((unsigned)id >= (unsigned)APP_PARAM_N) {
        return;
    }
    const app_param_t *p = &app_params[id];
    const uint8_t *f = &((const uint8_t *)cfg)[p->offset];
    if (p->type == (unsigned)APP_PARAM_REAL || p->type == (unsigned)APP_PARAM_VEC3) {
        (void)memcpy(v, f, p->size);
    } else if (p->size == 2u) {
        uint16_t u;
        (void)memcpy(&u, f, sizeof u);
        v[0] = (nav_real_t)u;
    } else if (p->size == 1u) {
        v[0] = (nav_real_t)f[0];
    } else {
        uint32_t u;
        (void)memcpy(&u, f, sizeof u);
        v[0] = (nav_real_t)u;
    }
}

int app_param_set(app_config_t *cfg, app_param_id_t id, const nav_real_t v[3])
{
    if (!app_param_in_range(id, v)) {
        return -1;
    }
    const app_param_t *p = &app_params[id];
    uint8_t *f = &((uint8_t *)cfg)[p->offset];
    if (p->type == (unsigned)APP_PARAM_REAL || p->type == (unsigned)APP_PARAM_VEC3) {
        (void)memcpy(f, v, p->size);
        return 0;
    }
    /* a whole number within the range (app_param_in_range) */
    const uint32_t u = (uint32_t)v[0];
    if (p->size == 2u) {
        const uint16_t u16 = (uint16_t)u;
        (void)memcpy(f, &u16, sizeof u16);
    } else if (p->size == 1u) {
        f[0] = (uint8_t)u;
    } else {
        (void)memcpy(f, &u, sizeof u);
    }
    return 0;
}

static int value_in_range(const app_param_t *p, nav_real_t x)
{
    const int lo = p->min_exclusive ? x > p->min_si : x >= p->min_si;
    return lo && x <= p->max_si; /* false for NaN */
}

int app_param_in_range(app_param_id_t id, const nav_real_t v[3])
{
    if ((unsigned)id >= (unsigned)APP_PARAM_N) {
        return 0;
    }
    const app_param_t *p = &app_params[id];
    if (p->vehicle_default && same(v[0], NAV_C(0.0))) {
        return 1; /* the defaults' placeholder, replaced by the vehicle profile's */
    }
    int n = 1;
    if (p->type == (unsigned)APP_PARAM_VEC3) {
        n = 3;
    }
    for (int i = 0; i < n; i++) {
        if (!value_in_range(p, v[i])) {
            return 0;
        }
    }
    if (p->type == (unsigned)APP_PARAM_U16 || p->type == (unsigned)APP_PARAM_ENUM) {
        return same(v[0], (nav_real_t)(int32_t)v[0]); /* a whole number */
    }
    return 1;
}

/* every identifier a standard (11-bit) one, none used twice */
static int can_ids_ok(const uint32_t ids[NAVECU_MSG_N])
{
    for (int i = 0; i < (int)NAVECU_MSG_N; i++) {
        if (ids[i] > 0x7FFu) {
            return 0;
        }
        for (int j = 0; j < i; j++) {
            if (ids[j] == ids[i]) {
                return 0;
            }
        }
    }
    return 1;
}

app_config_rule_t app_config_check(const app_config_t *cfg)
{
    for (int k = 0; k < (int)APP_PARAM_N; k++) {
        const app_param_id_t id = (app_param_id_t)k;
        nav_real_t v[3];
        app_param_get(cfg, id, v);
        if (!app_param_in_range(id, v) ||
            (app_params[k].vehicle_default && !(v[0] > NAV_C(0.0)))) {
            return APP_CONFIG_RANGE;
        }
    }
    for (int i = 0; i < (int)NAVECU_MSG_N; i++) {
        if (cfg->can_ids[i] == cfg->uds_request_id || cfg->can_ids[i] == cfg->uds_response_id) {
            return APP_CONFIG_UDS_ON_NAV; /* a diagnostic frame would be taken for one of
                                             navecu's messages */
        }
    }
    if (!can_ids_ok(cfg->can_ids)) {
        return APP_CONFIG_CAN_IDS;
    }
    if (cfg->uds_request_id == cfg->uds_response_id) {
        return APP_CONFIG_UDS_SAME;
    }
    if (cfg->nav_rate_hz > cfg->imu_rate_hz || cfg->status_rate_hz > cfg->imu_rate_hz ||
        cfg->dyn_rate_hz > cfg->imu_rate_hz) {
        return APP_CONFIG_RATES;
    }
    return APP_CONFIG_OK;
}

int app_config_valid(const app_config_t *cfg)
{
    return app_config_check(cfg) == APP_CONFIG_OK;
}
