/*
 * uds.h - the UDS server (ISO 14229-1): one request in, its response out. Pure: no HAL,
 * no clock, no allocation, no recursion, no global state. The transport (ISO-TP, isotp.h)
 * and the data behind the data identifiers belong to the caller (firmware/app/app_uds.c):
 * the server reaches them only through uds_if_t below.
 *
 * Services (docs/can.md, "Diagnostics (UDS)", has every request and response byte):
 *   0x10 DiagnosticSessionControl  0x01 default, 0x03 extended, 0x02 programming when the
 *                                  application has a session_change; response with P2/P2*
 *   0x11 ECUReset                  0x01 hardReset, unlocked only; done after the response
 *   0x22 ReadDataByIdentifier      1..UDS_MAX_READ_DIDS DIDs per request
 *   0x27 SecurityAccess            0x01 requestSeed / 0x02 sendKey, extended or programming
 *                                  session (as 0x2E and 0x31: any non-default session)
 *   0x2E WriteDataByIdentifier     extended session and unlocked
 *   0x31 RoutineControl            0x01 startRoutine, extended session and unlocked;
 *                                  0x11 when the application has no start_routine
 *   0x3E TesterPresent             0x00
 *   0x19 ReadDTCInformation        0x01 reportNumberOfDTCByStatusMask, 0x02
 *                                  reportDTCByStatusMask, 0x0A reportSupportedDTC; any session
 *   0x14 ClearDiagnosticInformation groupOfDTC 0xFFFFFF (all DTCs); any session
 * suppressPosRspMsgIndicationBit (bit 7 of the sub-function of 0x10, 0x11, 0x19, 0x27, 0x3E):
 * a positive response is not sent, a negative one is. Physical addressing only, so every
 * negative response is sent.
 *
 * Time: uds_handle and uds_poll take the caller's now_us (any monotonic microsecond
 * clock; the application passes the HAL's, as to isotp); a time that goes backwards counts
 * as no time elapsed. S3 (UDS_S3_US): a non-default session with no request for 5 s falls
 * back to the default session, locked.
 */
#ifndef NAVECU_UDS_H
#define NAVECU_UDS_H

#include <stddef.h>
#include <stdint.h>

/* service identifiers (request; the positive response is SID + 0x40) */
#define UDS_SID_SESSION 0x10u
#define UDS_SID_ECU_RESET 0x11u
#define UDS_SID_READ_DID 0x22u
#define UDS_SID_SECURITY 0x27u
#define UDS_SID_WRITE_DID 0x2Eu
#define UDS_SID_TESTER_PRESENT 0x3Eu
/* the fault memory (dtc branch) */
#define UDS_SID_CLEAR_DTC 0x14u   /* ClearDiagnosticInformation */
#define UDS_SID_READ_DTC 0x19u    /* ReadDTCInformation */
#define UDS_DTC_BY_STATUS_COUNT 0x01u  /* 0x19 reportNumberOfDTCByStatusMask */
#define UDS_DTC_BY_STATUS 0x02u        /* 0x19 reportDTCByStatusMask */
#define UDS_DTC_SUPPORTED 0x0Au        /* 0x19 reportSupportedDTC */
#define UDS_DTC_GROUP_ALL 0xFFFFFFu    /* 0x14 groupOfDTC: all groups */
#define UDS_DTC_FORMAT_J2012 0x00u     /* DTCFormatIdentifier SAE_J2012-DA_DTCFormat_00 */
#define UDS_SID_ROUTINE 0x31u     /* RoutineControl */
#define UDS_ROUTINE_START 0x01u   /* its startRoutine sub-function (the only one served) */
#define UDS_NEGATIVE 0x7Fu        /* a negative response: 7F SID NRC */
#define UDS_SUPPRESS_POS 0x80u    /* suppressPosRspMsgIndicationBit of a sub-function */

/* negative response codes, ISO 14229-1 Table A.1 (0: none, a positive response) */
#define UDS_NRC_OK 0x00u
#define UDS_NRC_SERVICE_NOT_SUPPORTED 0x11u
#define UDS_NRC_SUBFUNCTION_NOT_SUPPORTED 0x12u
#define UDS_NRC_INCORRECT_LENGTH 0x13u        /* incorrectMessageLengthOrInvalidFormat */
#define UDS_NRC_RESPONSE_TOO_LONG 0x14u
#define UDS_NRC_CONDITIONS_NOT_CORRECT 0x22u
#define UDS_NRC_REQUEST_SEQUENCE_ERROR 0x24u  /* sendKey without a seed */
#define UDS_NRC_REQUEST_OUT_OF_RANGE 0x31u
#define UDS_NRC_SECURITY_ACCESS_DENIED 0x33u
#define UDS_NRC_INVALID_KEY 0x35u
#define UDS_NRC_EXCEEDED_ATTEMPTS 0x36u
#define UDS_NRC_GENERAL_PROGRAMMING_FAILURE 0x72u
#define UDS_NRC_TIME_DELAY_NOT_EXPIRED 0x37u
#define UDS_NRC_RESPONSE_PENDING 0x78u  /* requestCorrectlyReceived-ResponsePending */
#define UDS_NRC_NOT_IN_ACTIVE_SESSION 0x7Fu   /* serviceNotSupportedInActiveSession */

/* sessions (0x10 sub-functions) */
#define UDS_SESSION_DEFAULT 0x01u
#define UDS_SESSION_PROGRAMMING 0x02u /* only with a session_change function (uds_if_t) */
#define UDS_SESSION_EXTENDED 0x03u

/* timing: P2 and P2* announced in the 0x10 response, S3 enforced */
#define UDS_P2_MS 50u         /* the server answers within 50 ms (sent in 1 ms units) */
#define UDS_P2_STAR_MS 5000u  /* after a 0x78 responsePending (sent in 10 ms units) */
#define UDS_S3_US 5000000u    /* S3server: 5 s without a request -> default session */

/* SecurityAccess: attempts and the delay after them */
#define UDS_MAX_ATTEMPTS 3u           /* wrong keys in a row that start the delay */
#define UDS_SECURITY_DELAY_US 10000000u /* 10 s of 0x37 after the third wrong key */
#define UDS_SEED_LEN 4u               /* seed and key: 4 bytes, big-endian */
/* The key of a seed: a DEMONSTRATION algorithm, NOT security (anyone who reads this can
 * compute it): key = rotl32(seed XOR UDS_KEY_XOR, 5) + UDS_KEY_ADD (mod 2^32). */
#define UDS_KEY_XOR 0x4E415645u       /* "NAVE" */
#define UDS_KEY_ADD 0x43553136u       /* "CU16" */

#define UDS_MAX_READ_DIDS 64u         /* DIDs one 0x22 request may name (every parameter
                                         and identification DID at once, with room) */

/*
 * What the server needs from its application. Every function is called from uds_handle
 * only, with the server's own arguments.
 *   read_did   write DID's value to buf (at most cap bytes): its length (> 0), 0 when the
 *              DID is not readable, or a value above cap when it would not fit.
 *   write_did  check and apply data[0..len) to DID: UDS_NRC_OK, or the NRC that refuses it
 *              (0x31 an unknown or read-only DID or a value out of range, 0x13 a wrong
 *              length, 0x22 not now). Called only in the extended session, unlocked.
 *   is_writable  1 if DID is one write_did may accept, else 0 (0x31 before 0x33: an
 *              unknown DID is out of range whatever the security state).
 * The fault memory (0x19, 0x14), optional: all four NULL, the services answer 0x11.
 *   dtc_count  the number of DTCs the ECU supports (their indices 0..count-1).
 *   dtc_get    DTC index's 3-byte number (bits 23..0) and its status byte: 0, or -1 for
 *              an index out of range.
 *   dtc_clear  clear the DTCs of groupOfDTC group (the server passes UDS_DTC_GROUP_ALL
 *              only): UDS_NRC_OK, or the NRC that refuses it (0x22 not now, 0x72 the NVM
 *              write failed).
 *   dtc_availability  the DTCStatusAvailabilityMask: the status bits the ECU supports.
 *   start_routine  (optional, NULL: 0x31 is serviceNotSupported) start routine rid with
 *              its option record data[0..len): UDS_NRC_OK once it is done, or the NRC
 *              (0x31 an unknown routine, 0x22 not now, 0x72 an NVM failure). Called only
 *              in the extended session, unlocked.
 *   has_routine  (needed by start_routine; NULL: no routine is known) 1 if rid is one of its routines, else 0: an unknown
 *              routine is 0x31 before 0x33, whatever the security state (ISO 14229-1's
 *              order for 0x31, as is_writable's for 0x2E).
 * Pluggable parts, optional (NULL: not there), used by the bootloader (firmware/boot):
 *   session_change  a 0x10 request for session (its sub-function, suppress bit off) is
 *              about to be accepted: UDS_NRC_OK lets it (the session changes, relocked), any
 *              other code is the negative response. Without it the programming session
 *              (0x02) is 0x12; with it, the function decides for every session.
 *   service    a service the server does not serve itself (e.g. 0x34, 0x36, 0x37): called
 *              with the request (req[0] its SID), the session and whether SecurityAccess
 *              is granted; writes its positive response's bytes after the SID at rsp[1..]
 *              (at most cap - 1), their count + 1 in *rsp_len, and returns UDS_NRC_OK, or
 *              the NRC (0x11 for a SID it does not serve either).
 * Functions are appended at the end (applications use designated initialisers).
 */
typedef struct {
    void *user;
    size_t (*read_did)(void *user, uint16_t did, uint8_t *buf, size_t cap);
    uint8_t (*write_did)(void *user, uint16_t did, const uint8_t *data, size_t len);
    int (*is_writable)(void *user, uint16_t did);
    size_t (*dtc_count)(void *user);
    int (*dtc_get)(void *user, size_t index, uint32_t *dtc, uint8_t *status);
    uint8_t (*dtc_clear)(void *user, uint32_t group);
    uint8_t (*dtc_availability)(void *user);
    uint8_t (*start_routine)(void *user, uint16_t rid, const uint8_t *data, size_t len);
    uint8_t (*session_change)(void *user, uint8_t session);
    uint8_t (*service)(void *user, uint8_t session, uint8_t unlocked, const uint8_t *req,
                       size_t len, uint8_t *rsp, size_t cap, size_t *rsp_len);
    int (*has_routine)(void *user, uint16_t rid);
} uds_if_t;

/* Counted, each saturating (never decreasing). */
typedef struct {
    uint32_t requests;       /* requests handled */
    uint32_t negative;       /* negative responses sent */
    uint32_t s3_timeouts;    /* falls back to the default session on S3 */
    uint32_t wrong_keys;     /* keys refused (0x35 and 0x36) */
} uds_counters_t;

/* The server's state: fixed size, caller-owned. */
typedef struct {
    uds_if_t itf;
    uds_counters_t cnt;
    uint8_t session;          /* UDS_SESSION_DEFAULT, _EXTENDED (or _PROGRAMMING) */
    uint8_t unlocked;         /* SecurityAccess level 0x01 granted */
    uint8_t seed_pending;     /* a seed was sent; its key is awaited */
    uint8_t attempts;         /* wrong keys in a row */
    uint8_t delay_on;         /* the delay after UDS_MAX_ATTEMPTS runs */
    uint8_t reset_pending;    /* an ECUReset was accepted: the caller resets after the
                                 response went out (uds_take_reset) */
    uint8_t pending_sent;     /* a 7F SID 78 went out for the request being served: its
                                 final response is sent even when suppressed */
    uint32_t seed;            /* the seed sent */
    uint32_t prng;            /* seed generator state (xorshift32), never 0 */
    uint64_t delay_start_us;
    uint64_t last_request_us; /* S3 start */
} uds_t;

/* A 7F SID 78 responsePending went out for the request being served (called from within
 * uds_handle's callbacks): ISO 14229-1 then wants the final response whatever the request's
 * suppressPosRspMsgIndicationBit says (the tester waits for it for P2*). */
void uds_pending_sent(uds_t *s);

/* Start in the default session, locked, no delay, counters 0. entropy mixes into the seed
 * generator (any value; the application passes its time). Returns 0, -1 for NULLs or an
 * interface without its three functions. */
int uds_init(uds_t *s, const uds_if_t *itf, uint32_t entropy);

/*
 * One request req[0..len) received at now_us: its response written to rsp (cap bytes,
 * >= 8), its length returned; 0 when no response is to be sent (suppressPosRsp on a
 * positive response, or len 0). A response that would not fit cap is 0x14.
 */
size_t uds_handle(uds_t *s, const uint8_t *req, size_t len, uint64_t now_us, uint8_t *rsp,
                  size_t cap);

/* The timers at now_us: S3 (back to the default session, locked) and the end of the
 * security delay. Call it from the main loop. */
void uds_poll(uds_t *s, uint64_t now_us);

/* 1 once after an accepted ECUReset (then 0): the caller resets when its response left. */
int uds_take_reset(uds_t *s);

/* Enter session (a bootloader started on a programming request: the response to that
 * request is then its own, uds_session_response), relocked, S3 from now_us. */
void uds_set_session(uds_t *s, uint8_t session, uint64_t now_us);

/* The positive response to 0x10 session (50 ss P2 P2*) at rsp (>= 6 bytes): 6. */
size_t uds_session_response(uint8_t session, uint8_t *rsp);

/* The demonstration key of a seed (UDS_KEY_XOR, UDS_KEY_ADD above). */
uint32_t uds_key_of_seed(uint32_t seed);

/* v at p[0..3], big-endian: UDS's byte order (a DID's values, a seed) */
void uds_put_u32(uint8_t *p, uint32_t v);

#endif /* NAVECU_UDS_H */
