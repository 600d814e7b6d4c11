/* uds.c - the UDS server (ISO 14229-1); see uds.h. */
#include "uds.h"

#include <string.h>

#define PRNG_NONZERO 0x2545F491u /* replaces a zero xorshift state */

static uint32_t elapsed_us_over(uint64_t now_us, uint64_t since_us, uint64_t limit_us)
{
    return (now_us > since_us && now_us - since_us >= limit_us) ? 1u : 0u;
}

static void count(uint32_t *c)
{
    if (*c != UINT32_MAX) {
        (*c)++;
    }
}

uint32_t uds_key_of_seed(uint32_t seed)
{
    const uint32_t x = seed ^ UDS_KEY_XOR;
    return ((x << 5) | (x >> 27)) + UDS_KEY_ADD;
}

static void lock(uds_t *s)
{
    s->unlocked = 0u;
    s->seed_pending = 0u;
}

int uds_init(uds_t *s, const uds_if_t *itf, uint32_t entropy)
{
    if (s == NULL || itf == NULL || itf->read_did == NULL || itf->write_did == NULL ||
        itf->is_writable == NULL) {
        return -1;
    }
    memset(s, 0, sizeof *s);
    s->itf = *itf;
    s->session = UDS_SESSION_DEFAULT;
    s->prng = entropy != 0u ? entropy : PRNG_NONZERO;
    return 0;
}

void uds_poll(uds_t *s, uint64_t now_us)
{
    if (s->session != UDS_SESSION_DEFAULT &&
        elapsed_us_over(now_us, s->last_request_us, UDS_S3_US)) {
        s->session = UDS_SESSION_DEFAULT;
        lock(s);
        count(&s->cnt.s3_timeouts);
    }
    if (s->delay_on && elapsed_us_over(now_us, s->delay_start_us, UDS_SECURITY_DELAY_US)) {
        s->delay_on = 0u;
    }
}

int uds_take_reset(uds_t *s)
{
    const int r = s->reset_pending ? 1 : 0;
    s->reset_pending = 0u;
    return r;
}

/* the result of one service: a negative response code, or the positive response's length
 * (written at rsp) and whether it is suppressed */
typedef struct {
    uint8_t nrc;
    uint8_t suppress;
    size_t len;
} result_t;

static result_t nrc(uint8_t code)
{
    const result_t r = {code, 0u, 0u};
    return r;
}

/* Out of line (noinline): GCC inlined it at each of its 12 calls, 56 bytes more of the
 * application's flash and 44 of the bootloader's (docs/target.md); per diagnostic
 * request only. */
__attribute__((noinline)) static result_t positive(size_t len, uint8_t suppress)
{
    const result_t r = {UDS_NRC_OK, suppress, len};
    return r;
}

static void put_u16(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 8);
    p[1] = (uint8_t)v;
}

void uds_put_u32(uint8_t *p, uint32_t v)
{
    put_u16(p, v >> 16);
    put_u16(&p[2], v & 0xFFFFu);
}

static uint32_t get_u32(const uint8_t *p)
{
    return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | p[3];
}

size_t uds_session_response(uint8_t session, uint8_t *rsp)
{
    rsp[0] = (uint8_t)(UDS_SID_SESSION + 0x40u);
    rsp[1] = session;
    put_u16(&rsp[2], UDS_P2_MS);
    put_u16(&rsp[4], UDS_P2_STAR_MS / 10u);
    return 6u;
}

void uds_set_session(uds_t *s, uint8_t session, uint64_t now_us)
{
    s->session = session;
    lock(s);
    s->last_request_us = now_us;
}

/* 0x10: 50 ss P2(ms, 2 bytes) P2*(10 ms, 2 bytes) */
static result_t session_control(uds_t *s, const uint8_t *req, size_t len, uint8_t *rsp)
{
    const uint8_t sub = (uint8_t)(req[1] & 0x7Fu);
    if (sub != UDS_SESSION_DEFAULT && sub != UDS_SESSION_EXTENDED &&
        (sub != UDS_SESSION_PROGRAMMING || s->itf.session_change == NULL)) {
        return nrc(UDS_NRC_SUBFUNCTION_NOT_SUPPORTED);
    }
    if (len != 2u) {
        return nrc(UDS_NRC_INCORRECT_LENGTH);
    }
    if (s->itf.session_change != NULL) {
        const uint8_t code = s->itf.session_change(s->itf.user, sub);
        if (code != UDS_NRC_OK) {
            return nrc(code);
        }
    }
    s->session = sub;
    lock(s); /* every session transition relocks */
    return positive(uds_session_response(sub, rsp), req[1] & UDS_SUPPRESS_POS);
}

/* 0x11 01: 51 01, the reset done by the caller once the response left */
static result_t ecu_reset(uds_t *s, const uint8_t *req, size_t len, uint8_t *rsp)
{
    const uint8_t sub = (uint8_t)(req[1] & 0x7Fu);
    if (sub != 0x01u) {
        return nrc(UDS_NRC_SUBFUNCTION_NOT_SUPPORTED);
    }
    if (!s->unlocked) {
        return nrc(UDS_NRC_SECURITY_ACCESS_DENIED);
    }
    if (len != 2u) {
        return nrc(UDS_NRC_INCORRECT_LENGTH);
    }
    s->reset_pending = 1u;
    rsp[1] = sub;
    return positive(2u, req[1] & UDS_SUPPRESS_POS);
}

/* 0x3E 00: 7E 00 */
static result_t tester_present(const uint8_t *req, size_t len, uint8_t *rsp)
{
    if ((req[1] & 0x7Fu) != 0u) {
        return nrc(UDS_NRC_SUBFUNCTION_NOT_SUPPORTED);
    }
    if (len != 2u) {
        return nrc(UDS_NRC_INCORRECT_LENGTH);
    }
    rsp[1] = 0u;
    return positive(2u, req[1] & UDS_SUPPRESS_POS);
}

/* 0x27 01: 67 01 seed(4), 0x27 02 key(4): 67 02 */
static result_t security_access(uds_t *s, const uint8_t *req, size_t len, uint8_t *rsp,
                                uint64_t now_us)
{
    const uint8_t sub = (uint8_t)(req[1] & 0x7Fu);
    const uint8_t suppress = req[1] & UDS_SUPPRESS_POS;
    if (sub != 0x01u && sub != 0x02u) {
        return nrc(UDS_NRC_SUBFUNCTION_NOT_SUPPORTED);
    }
    if (len != (sub == 0x01u ? 2u : 2u + UDS_SEED_LEN)) {
        return nrc(UDS_NRC_INCORRECT_LENGTH);
    }
    if (s->delay_on) {
        return nrc(UDS_NRC_TIME_DELAY_NOT_EXPIRED);
    }
    rsp[1] = sub;
    if (sub == 0x01u) {
        if (s->unlocked) {
            uds_put_u32(&rsp[2], 0u); /* already unlocked: the seed is 0 */
            return positive(2u + UDS_SEED_LEN, suppress);
        }
        uint32_t x = s->prng ^ (uint32_t)now_us;
        if (x == 0u) {
            x = PRNG_NONZERO;
        }
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        s->prng = x;
        s->seed = x; /* never 0: xorshift keeps a nonzero state nonzero */
        s->seed_pending = 1u;
        uds_put_u32(&rsp[2], s->seed);
        return positive(2u + UDS_SEED_LEN, suppress);
    }
    if (!s->seed_pending) {
        return nrc(UDS_NRC_REQUEST_SEQUENCE_ERROR);
    }
    s->seed_pending = 0u; /* a seed is good for one key */
    if (get_u32(&req[2]) != uds_key_of_seed(s->seed)) {
        count(&s->cnt.wrong_keys);
        s->attempts++;
        if (s->attempts >= UDS_MAX_ATTEMPTS) {
            s->attempts = 0u;
            s->delay_on = 1u;
            s->delay_start_us = now_us;
            return nrc(UDS_NRC_EXCEEDED_ATTEMPTS);
        }
        return nrc(UDS_NRC_INVALID_KEY);
    }
    s->attempts = 0u;
    s->unlocked = 1u;
    return positive(2u, suppress);
}

/* 0x22 DID DID ..: 62 DID data DID data .. */
static result_t read_data(uds_t *s, const uint8_t *req, size_t len, uint8_t *rsp, size_t cap)
{
    if (len < 3u || (len - 1u) % 2u != 0u || (len - 1u) / 2u > UDS_MAX_READ_DIDS) {
        return nrc(UDS_NRC_INCORRECT_LENGTH);
    }
    size_t pos = 1u;
    uint32_t found = 0u;
    for (size_t i = 1u; i + 1u < len; i += 2u) {
        const uint16_t did = (uint16_t)(((uint32_t)req[i] << 8) | req[i + 1u]);
        if (pos + 2u >= cap) {
            return nrc(UDS_NRC_RESPONSE_TOO_LONG);
        }
        const size_t n = s->itf.read_did(s->itf.user, did, &rsp[pos + 2u], cap - pos - 2u);
        if (n == 0u) {
            continue; /* not supported: left out; none at all is 0x31 */
        }
        if (n > cap - pos - 2u) {
            return nrc(UDS_NRC_RESPONSE_TOO_LONG);
        }
        put_u16(&rsp[pos], did);
        pos += 2u + n;
        found++;
    }
    if (found == 0u) {
        return nrc(UDS_NRC_REQUEST_OUT_OF_RANGE);
    }
    return positive(pos, 0u);
}

/* 0x2E DID data..: 6E DID */
static result_t write_data(uds_t *s, const uint8_t *req, size_t len, uint8_t *rsp)
{
    if (len < 4u) {
        return nrc(UDS_NRC_INCORRECT_LENGTH);
    }
    const uint16_t did = (uint16_t)(((uint32_t)req[1] << 8) | req[2]);
    if (!s->itf.is_writable(s->itf.user, did)) {
        return nrc(UDS_NRC_REQUEST_OUT_OF_RANGE);
    }
    if (!s->unlocked) {
        return nrc(UDS_NRC_SECURITY_ACCESS_DENIED);
    }
    const uint8_t code = s->itf.write_did(s->itf.user, did, &req[3], len - 3u);
    if (code != UDS_NRC_OK) {
        return nrc(code);
    }
    rsp[1] = req[1];
    rsp[2] = req[2];
    return positive(3u, 0u);
}

/* ---- the fault memory: 0x19 ReadDTCInformation, 0x14 ClearDiagnosticInformation ---- */

static int has_fault_memory(const uds_t *s)
{
    return (s->itf.dtc_count != NULL && s->itf.dtc_get != NULL && s->itf.dtc_clear != NULL &&
            s->itf.dtc_availability != NULL) ? 1 : 0;
}

/* 0x19 01 mask: 59 01 avail 00 nn nn; 0x19 02 mask: 59 02 avail [DTC(3) status]..;
 * 0x19 0A: 59 0A avail [DTC(3) status].. (every DTC) */
static result_t read_dtc_info(uds_t *s, const uint8_t *req, size_t len, uint8_t *rsp,
                              size_t cap)
{
    const uint8_t sub = (uint8_t)(req[1] & 0x7Fu);
    const uint8_t suppress = req[1] & UDS_SUPPRESS_POS;
    if (sub != UDS_DTC_BY_STATUS_COUNT && sub != UDS_DTC_BY_STATUS && sub != UDS_DTC_SUPPORTED) {
        return nrc(UDS_NRC_SUBFUNCTION_NOT_SUPPORTED);
    }
    if (len != (sub == UDS_DTC_SUPPORTED ? 2u : 3u)) {
        return nrc(UDS_NRC_INCORRECT_LENGTH);
    }
    const uint8_t avail = s->itf.dtc_availability(s->itf.user);
    /* reportSupportedDTC: every DTC, whatever its status */
    const uint8_t mask = sub == UDS_DTC_SUPPORTED ? 0xFFu : req[2];
    const size_t n = s->itf.dtc_count(s->itf.user);
    rsp[1] = sub;
    rsp[2] = avail;
    size_t pos = 3u;
    uint32_t matched = 0u;
    for (size_t i = 0u; i < n; i++) {
        uint32_t dtc = 0u;
        uint8_t st = 0u;
        if (s->itf.dtc_get(s->itf.user, i, &dtc, &st) != 0) {
            continue;
        }
        st &= avail; /* only the supported bits are reported */
        if (sub != UDS_DTC_SUPPORTED && (st & mask) == 0u) {
            continue;
        }
        matched++;
        if (sub == UDS_DTC_BY_STATUS_COUNT) {
            continue;
        }
        if (pos + 4u > cap) {
            return nrc(UDS_NRC_RESPONSE_TOO_LONG);
        }
        rsp[pos] = (uint8_t)(dtc >> 16);
        rsp[pos + 1u] = (uint8_t)(dtc >> 8);
        rsp[pos + 2u] = (uint8_t)dtc;
        rsp[pos + 3u] = st;
        pos += 4u;
    }
    if (sub == UDS_DTC_BY_STATUS_COUNT) {
        rsp[3] = UDS_DTC_FORMAT_J2012;
        put_u16(&rsp[4], matched > 0xFFFFu ? 0xFFFFu : matched);
        pos = 6u;
    }
    return positive(pos, suppress);
}

/* 0x14 GG GG GG: 54 (groupOfDTC 0xFFFFFF only) */
static result_t clear_dtc(uds_t *s, const uint8_t *req, size_t len)
{
    if (len != 4u) {
        return nrc(UDS_NRC_INCORRECT_LENGTH);
    }
    const uint32_t group = ((uint32_t)req[1] << 16) | ((uint32_t)req[2] << 8) | req[3];
    if (group != UDS_DTC_GROUP_ALL) {
        return nrc(UDS_NRC_REQUEST_OUT_OF_RANGE);
    }
    const uint8_t code = s->itf.dtc_clear(s->itf.user, group);
    if (code != UDS_NRC_OK) {
        return nrc(code);
    }
    return positive(1u, 0u);
}

/* 0x31 01 RID [option record]: 71 01 RID (startRoutine only; extended session, unlocked) */
static result_t routine_control(uds_t *s, const uint8_t *req, size_t len, uint8_t *rsp)
{
    const uint8_t sub = (uint8_t)(req[1] & 0x7Fu);
    if (sub != UDS_ROUTINE_START) {
        return nrc(UDS_NRC_SUBFUNCTION_NOT_SUPPORTED);
    }
    if (len < 4u) {
        return nrc(UDS_NRC_INCORRECT_LENGTH);
    }
    const uint16_t rid = (uint16_t)(((uint32_t)req[2] << 8) | req[3]);
    if (s->itf.has_routine == NULL || s->itf.has_routine(s->itf.user, rid) == 0) {
        return nrc(UDS_NRC_REQUEST_OUT_OF_RANGE);
    }
    if (!s->unlocked) {
        return nrc(UDS_NRC_SECURITY_ACCESS_DENIED);
    }
    const uint8_t code = s->itf.start_routine(s->itf.user, rid, &req[4], len - 4u);
    if (code != UDS_NRC_OK) {
        return nrc(code);
    }
    rsp[1] = sub;
    rsp[2] = req[2];
    rsp[3] = req[3];
    return positive(4u, req[1] & UDS_SUPPRESS_POS);
}

/* 1 for the services whose byte 1 is a sub-function */
static int has_subfunction(uint8_t sid)
{
    switch (sid) {
    case UDS_SID_SESSION:
    case UDS_SID_ECU_RESET:
    case UDS_SID_SECURITY:
    case UDS_SID_TESTER_PRESENT:
    case UDS_SID_ROUTINE:
        return 1;
    default:
        return 0;
    }
}

/* 1 for the services of a non-default session only (extended, or a bootloader's
 * programming session) */
static int extended_only(uint8_t sid)
{
    return (sid == UDS_SID_SECURITY || sid == UDS_SID_WRITE_DID || sid == UDS_SID_ROUTINE) ? 1
                                                                                         : 0;
}

/* a service of the application's (uds_if_t.service), else serviceNotSupported */
static result_t other_service(uds_t *s, const uint8_t *req, size_t len, uint8_t *rsp,
                              size_t cap)
{
    if (s->itf.service == NULL) {
        return nrc(UDS_NRC_SERVICE_NOT_SUPPORTED);
    }
    size_t n = 0u;
    const uint8_t code =
        s->itf.service(s->itf.user, s->session, s->unlocked, req, len, rsp, cap, &n);
    if (code != UDS_NRC_OK) {
        return nrc(code);
    }
    if (n < 1u || n > cap) {
        return nrc(UDS_NRC_GENERAL_PROGRAMMING_FAILURE); /* the service broke its contract */
    }
    return positive(n, 0u);
}

void uds_pending_sent(uds_t *s)
{
    s->pending_sent = 1u;
}

size_t uds_handle(uds_t *s, const uint8_t *req, size_t len, uint64_t now_us, uint8_t *rsp,
                  size_t cap)
{
    if (len == 0u || cap < 8u) {
        return 0u;
    }
    uds_poll(s, now_us); /* an S3 or a delay that ended before this request */
    s->pending_sent = 0u;
    count(&s->cnt.requests);
    s->last_request_us = now_us; /* S3 restarts with every request */
    const uint8_t sid = req[0];
    result_t r;
    /* (0x19 has one when the fault memory is there: else it is 0x11 whatever its length) */
    int has_sub = has_subfunction(sid);
    if (sid == UDS_SID_READ_DTC && has_fault_memory(s)) {
        has_sub = 1;
    }
    /* ISO 14229-1 Figure 5 / 7 order: the service (0x11), the session (0x7F), the minimum
     * length (0x13), the sub-function (0x12), then each service's own checks */
    if (sid == UDS_SID_ROUTINE && s->itf.start_routine == NULL) {
        r = nrc(UDS_NRC_SERVICE_NOT_SUPPORTED); /* an application without routines */
    } else if (extended_only(sid) && s->session == UDS_SESSION_DEFAULT) {
        r = nrc(UDS_NRC_NOT_IN_ACTIVE_SESSION);
    } else if (has_sub && len < 2u) {
        r = nrc(UDS_NRC_INCORRECT_LENGTH); /* no sub-function at all */
    } else {
        switch (sid) {
        case UDS_SID_SESSION:
            r = session_control(s, req, len, rsp);
            break;
        case UDS_SID_ECU_RESET:
            r = ecu_reset(s, req, len, rsp);
            break;
        case UDS_SID_READ_DID:
            r = read_data(s, req, len, rsp, cap);
            break;
        case UDS_SID_SECURITY:
            r = security_access(s, req, len, rsp, now_us);
            break;
        case UDS_SID_WRITE_DID:
            r = write_data(s, req, len, rsp);
            break;
        case UDS_SID_TESTER_PRESENT:
            r = tester_present(req, len, rsp);
            break;
        case UDS_SID_READ_DTC:
            r = has_fault_memory(s) ? read_dtc_info(s, req, len, rsp, cap)
                                    : nrc(UDS_NRC_SERVICE_NOT_SUPPORTED);
            break;
        case UDS_SID_CLEAR_DTC:
            r = has_fault_memory(s) ? clear_dtc(s, req, len) : nrc(UDS_NRC_SERVICE_NOT_SUPPORTED);
            break;
        case UDS_SID_ROUTINE:
            r = routine_control(s, req, len, rsp);
            break;
        default:
            r = other_service(s, req, len, rsp, cap);
            break;
        }
    }
    if (r.nrc != UDS_NRC_OK) {
        count(&s->cnt.negative);
        rsp[0] = (uint8_t)UDS_NEGATIVE;
        rsp[1] = sid;
        rsp[2] = r.nrc;
        return 3u;
    }
    if (r.suppress && s->pending_sent == 0u) {
        return 0u;
    }
    rsp[0] = (uint8_t)(sid + 0x40u);
    return r.len;
}
