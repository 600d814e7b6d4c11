/*
 * isotp_peer.c - the firmware's ISO-TP transport (firmware/diag/isotp.c) on a live
 * SocketCAN bus, for tests against another implementation (tests/python/test_isotp_peer.py,
 * tools/vcan/isotp_check.py: can-isotp as the tester).
 *
 * A small server on one channel: every message received is answered on the response ID,
 *   01 HH LL        -> a generated message of 0xHHLL bytes, byte i = i mod 251
 *   anything else   -> the same bytes back (echo)
 * with the channel's flow control, padding and timeouts set from the command line. It is
 * a board like host_sim/: it reads the HAL clock (CLOCK_REALTIME, the clock of the kernel's
 * receive timestamps) and passes the time to the transport, which reads none itself.
 *
 * Output: one JSON object a line on stdout, flushed at once:
 *   {"event":"ready",...}                       the socket is open
 *   {"event":"rx","len":N,"t_us":T}              a message taken from the transport
 *   {"event":"tx","len":N,"t_us":T}              a response started
 *   {"event":"count","name":C,"value":V,"t_us":T} a counter of isotp_counters_t moved
 *   {"event":"summary",...every counter...}      at the end
 * Ends on SIGINT/SIGTERM or after --duration-s. Exit status 0; 1 when the interface
 * cannot be opened; 2 on a usage error.
 *
 * Why a program of its own rather than an option of host_sim/navecu: the transport is not
 * wired into the application yet (that is the UDS server's part of issue #16), and a
 * separate server keeps the navigation executable and its regression outputs unchanged
 * while the transport is tested end to end against an independent peer.
 */
#include <inttypes.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hal_linux.h"
#include "hal_socketcan.h"
#include "isotp.h"

static volatile sig_atomic_t stop;

static void on_signal(int sig)
{
    (void)sig;
    stop = 1;
}

static hal_t hal;
static isotp_t ch;
static uint8_t req[ISOTP_MAX_LEN];
static uint8_t rsp[ISOTP_MAX_LEN];

static int tx(void *user, const hal_can_frame_t *f)
{
    return hal_can_send(user, f);
}

typedef struct {
    const char *name;
    size_t off;
} counter_t;

#define C(n) {#n, offsetof(isotp_counters_t, n)}
static const counter_t counters[] = {
    C(rx_msgs),       C(tx_msgs),       C(rx_invalid),    C(rx_unexpected), C(rx_wrong_sn),
    C(rx_timeout_cr), C(rx_timeout_ar), C(rx_overflow),   C(rx_busy),       C(rx_wft_ovrn),
    C(wait_sent),     C(tx_timeout_as), C(tx_timeout_bs), C(tx_overflow),   C(tx_invalid_fs),
    C(tx_wft_ovrn),   C(wait_received), C(tx_refused),
};

static uint32_t counter(const isotp_counters_t *c, size_t k)
{
    uint32_t v;
    memcpy(&v, (const char *)c + counters[k].off, sizeof v);
    return v;
}

/* print every counter that moved since *last */
static void report(isotp_counters_t *last, uint64_t now)
{
    for (size_t k = 0; k < sizeof counters / sizeof counters[0]; k++) {
        const uint32_t v = counter(&ch.cnt, k);
        if (v != counter(last, k)) {
            printf("{\"event\":\"count\",\"name\":\"%s\",\"value\":%" PRIu32 ",\"t_us\":%" PRIu64 "}\n",
                   counters[k].name, v, now);
        }
    }
    *last = ch.cnt;
    fflush(stdout);
}

static int parse_u32(const char *s, uint32_t max, uint32_t *out)
{
    char *end = NULL;
    const unsigned long v = strtoul(s, &end, 0);
    if (s[0] == '\0' || *end != '\0' || v > max) {
        return -1;
    }
    *out = (uint32_t)v;
    return 0;
}

static void usage(void)
{
    fprintf(stderr,
            "usage: isotp_peer --can IFACE [--rx-id ID] [--tx-id ID] [--bs N] [--stmin RAW]\n"
            "       [--pad BYTE] [--no-padding] [--wft-max N] [--wait-rx-max N]\n"
            "       [--wait-period-ms MS] [--n-as-ms MS] [--n-ar-ms MS] [--n-bs-ms MS]\n"
            "       [--n-cr-ms MS] [--hold-ms MS] [--duration-s S]\n"
            "defaults: rx 0x7A0, tx 0x7A8, the transport's (isotp_config_defaults)\n");
}

int main(int argc, char **argv)
{
    const char *iface = NULL;
    uint32_t rx_id = 0x7A0u, tx_id = 0x7A8u, hold_ms = 0u, duration_s = 0u;
    isotp_config_t cfg;
    isotp_config_defaults(&cfg, rx_id, tx_id);
    int id_set = 0;
    /* the options that set one field: byte values, and times given in ms */
    struct {
        const char *opt;
        uint8_t *field;
    } const u8_opts[] = {{"--bs", &cfg.block_size}, {"--stmin", &cfg.st_min},
                         {"--pad", &cfg.pad_byte}, {"--wft-max", &cfg.wft_max}};
    struct {
        const char *opt;
        uint32_t *us;
    } const ms_opts[] = {{"--wait-period-ms", &cfg.wait_period_us}, {"--n-as-ms", &cfg.n_as_us},
                         {"--n-ar-ms", &cfg.n_ar_us}, {"--n-bs-ms", &cfg.n_bs_us},
                         {"--n-cr-ms", &cfg.n_cr_us}};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = (i + 1 < argc) ? argv[i + 1] : NULL;
        uint32_t x = 0u;
        int bad = 0, known = 0;
        if (strcmp(a, "--no-padding") == 0) {
            cfg.padding = 0u;
            continue;
        }
        if (v == NULL) {
            usage();
            return 2;
        }
        i++;
        for (size_t k = 0; k < sizeof u8_opts / sizeof u8_opts[0]; k++) {
            if (strcmp(a, u8_opts[k].opt) == 0) {
                known = 1;
                bad = parse_u32(v, 255u, &x);
                *u8_opts[k].field = (uint8_t)x;
            }
        }
        for (size_t k = 0; k < sizeof ms_opts / sizeof ms_opts[0]; k++) {
            if (strcmp(a, ms_opts[k].opt) == 0) {
                known = 1;
                bad = parse_u32(v, 60000u, &x);
                *ms_opts[k].us = x * 1000u;
            }
        }
        if (known != 0) {
            /* set above */
        } else if (strcmp(a, "--can") == 0) {
            iface = v;
        } else if (strcmp(a, "--rx-id") == 0) {
            bad = parse_u32(v, 0x7FFu, &rx_id);
            id_set = 1;
        } else if (strcmp(a, "--tx-id") == 0) {
            bad = parse_u32(v, 0x7FFu, &tx_id);
            id_set = 1;
        } else if (strcmp(a, "--wait-rx-max") == 0) {
            bad = parse_u32(v, 65535u, &x);
            cfg.wait_rx_max = (uint16_t)x;
        } else if (strcmp(a, "--hold-ms") == 0) {
            bad = parse_u32(v, 60000u, &hold_ms);
        } else if (strcmp(a, "--duration-s") == 0) {
            bad = parse_u32(v, 86400u, &duration_s);
        } else {
            bad = 1;
        }
        if (bad != 0) {
            fprintf(stderr, "isotp_peer: bad option %s %s\n", a, v);
            usage();
            return 2;
        }
    }
    if (id_set != 0) {
        cfg.rx_id = rx_id;
        cfg.tx_id = tx_id;
    }
    if (iface == NULL || isotp_init(&ch, &cfg) != 0) {
        fprintf(stderr, "isotp_peer: %s\n", iface == NULL ? "--can IFACE is required"
                                                         : "the configuration is refused by isotp_init");
        usage();
        return 2;
    }
    const uint32_t ids[1] = {cfg.rx_id};
    if (hal_socketcan_open(&hal, iface, ids, 1u, NULL, NULL) != 0) {
        perror("isotp_peer: cannot open the CAN interface");
        return 1;
    }
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);

    const uint64_t t0 = hal_time_us(&hal);
    const uint64_t end = duration_s != 0u ? t0 + (uint64_t)duration_s * 1000000u : UINT64_MAX;
    printf("{\"event\":\"ready\",\"rx_id\":%" PRIu32 ",\"tx_id\":%" PRIu32 ",\"bs\":%u,\"stmin\":%u,"
           "\"padding\":%u,\"max_len\":%u,\"t_us\":%" PRIu64 "}\n",
           cfg.rx_id, cfg.tx_id, cfg.block_size, cfg.st_min, cfg.padding, (unsigned)ISOTP_MAX_LEN, t0);
    fflush(stdout);

    isotp_counters_t last = ch.cnt;
    uint32_t msgs_seen = 0u;
    uint64_t ready_at = 0u;
    while (stop == 0) {
        uint64_t now = hal_time_us(&hal);
        if (now >= end) {
            break;
        }
        /* sleep until a frame arrives, or briefly while a frame or a WAIT may be due */
        int wait_ms = 10;
        if (ch.tx_state == ISOTP_TX_SEND) {
            wait_ms = (ch.tx_due_us > now + 1000u) ? 1 : 0;
        } else if (ch.rx_state == ISOTP_RX_WAIT_BUF || ch.ready_len != 0u) {
            wait_ms = 1;
        }
        if (hal_socketcan_wait(&hal, wait_ms) < 0) {
            perror("isotp_peer: poll");
            break;
        }
        hal_can_frame_t f;
        while (hal_can_receive(&hal, &f) == 0) {
            (void)isotp_on_frame(&ch, &f, f.t_us);
            report(&last, f.t_us);
            now = hal_time_us(&hal);
            (void)isotp_poll(&ch, now, tx, &hal);
            report(&last, now);
        }
        now = hal_time_us(&hal);
        if (ch.cnt.rx_msgs != msgs_seen) {
            msgs_seen = ch.cnt.rx_msgs;
            ready_at = now; /* the hold starts when the message is complete */
        }
        /* the server: take the request once held long enough and the last answer is out */
        size_t len = 0u;
        if (ch.ready_len != 0u && isotp_tx_busy(&ch) == 0 && now - ready_at >= (uint64_t)hold_ms * 1000u &&
            isotp_receive(&ch, req, sizeof req, &len) == 0) {
            printf("{\"event\":\"rx\",\"len\":%zu,\"t_us\":%" PRIu64 "}\n", len, now);
            size_t out = len;
            if (len == 3u && req[0] == 0x01u) {
                out = ((size_t)req[1] << 8) | req[2];
                for (size_t k = 0; k < out && k < sizeof rsp; k++) {
                    rsp[k] = (uint8_t)(k % 251u);
                }
            } else {
                memcpy(rsp, req, len);
            }
            if (out >= 1u && out <= ISOTP_MAX_LEN && isotp_send(&ch, rsp, out, now) == 0) {
                printf("{\"event\":\"tx\",\"len\":%zu,\"t_us\":%" PRIu64 "}\n", out, now);
            }
            fflush(stdout);
        }
        (void)isotp_poll(&ch, now, tx, &hal);
        report(&last, now);
    }
    printf("{\"event\":\"summary\"");
    for (size_t k = 0; k < sizeof counters / sizeof counters[0]; k++) {
        printf(",\"%s\":%" PRIu32, counters[k].name, counter(&ch.cnt, k));
    }
    printf(",\"socket_io_errors\":%" PRIu32 "}\n", hal_socketcan_io_errors(&hal));
    fflush(stdout);
    hal_linux_close(&hal);
    return 0;
}
