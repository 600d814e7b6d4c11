/*
 * test_hal_linux.c - the Linux host HAL: candump log replay (every valid form, every
 * malformed kind, exact timestamps, end of file), the TX log byte for byte, NVM bounds,
 * persistence and flash semantics, the watchdog counter, and a seeded garbage replay that
 * must not crash.
 *
 * Every file lives in a directory made by mkdtemp in the group setup and removed in the
 * group teardown.
 */
#include <dirent.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "hal_linux.h"

static char tmp_dir[256];

/* tmp_dir/name into out (size PATH_LEN) */
#define PATH_LEN 512
static void tmp_path(char *out, const char *name)
{
    const int n = snprintf(out, PATH_LEN, "%s/%s", tmp_dir, name);
    assert_true(n > 0 && n < PATH_LEN);
}

/* write n bytes of data to tmp_dir/name (binary-safe), path into out */
static void write_file_n(char *out, const char *name, const char *data, size_t n)
{
    tmp_path(out, name);
    FILE *fp = fopen(out, "wb");
    assert_non_null(fp);
    assert_int_equal(fwrite(data, 1, n, fp), n);
    assert_int_equal(fclose(fp), 0);
}

static void write_file(char *out, const char *name, const char *text)
{
    write_file_n(out, name, text, strlen(text));
}

/* read tmp file into buf (NUL-terminated), returns its length */
static size_t read_file(const char *path, char *buf, size_t cap)
{
    FILE *fp = fopen(path, "rb");
    assert_non_null(fp);
    const size_t n = fread(buf, 1, cap - 1, fp);
    assert_int_equal(ferror(fp), 0);
    assert_int_equal(fclose(fp), 0);
    buf[n] = '\0';
    return n;
}

static int group_setup(void **state)
{
    (void)state;
    const char *base = getenv("TMPDIR");
    if (base == NULL || base[0] == '\0') {
        base = "/tmp";
    }
    const int n = snprintf(tmp_dir, sizeof tmp_dir, "%s/test_hal_linux.XXXXXX", base);
    if (n < 0 || (size_t)n >= sizeof tmp_dir || mkdtemp(tmp_dir) == NULL) {
        return -1;
    }
    return 0;
}

static int group_teardown(void **state)
{
    (void)state;
    DIR *d = opendir(tmp_dir);
    if (d == NULL) {
        return -1;
    }
    struct dirent *e;
    char p[PATH_LEN];
    while ((e = readdir(d)) != NULL) {
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0) {
            (void)snprintf(p, sizeof p, "%s/%s", tmp_dir, e->d_name);
            (void)unlink(p);
        }
    }
    (void)closedir(d);
    return rmdir(tmp_dir) == 0 ? 0 : -1;
}

/* open a HAL replaying text (no TX, in-memory NVM) */
static void open_rx_text(hal_t *hal, const char *name, const char *text)
{
    char p[PATH_LEN];
    write_file(p, name, text);
    assert_int_equal(hal_linux_open(hal, p, NULL, NULL), 0);
}

static void expect_frame(hal_t *hal, uint32_t id, uint8_t ext, uint8_t dlc,
                         const uint8_t *data, uint64_t t_us)
{
    hal_can_frame_t f;
    memset(&f, 0xA5, sizeof f);
    assert_int_equal(hal_can_receive(hal, &f), 0);
    assert_int_equal(f.id, id);
    assert_int_equal(f.extended, ext);
    assert_int_equal(f.dlc, dlc);
    if (dlc > 0) {
        assert_memory_equal(f.data, data, dlc);
    }
    assert_true(f.t_us == t_us);
    assert_true(hal_time_us(hal) == t_us);
}

static void expect_end(hal_t *hal)
{
    hal_can_frame_t f;
    assert_int_equal(hal_can_receive(hal, &f), HAL_ENODATA);
    assert_int_equal(hal_can_receive(hal, &f), HAL_ENODATA);
}

/* ---- RX: valid forms ---- */

static void test_rx_valid_forms(void **state)
{
    (void)state;
    static hal_t hal;
    static const uint8_t dead[] = {0xDE, 0xAD, 0xBE, 0xEF};
    static const uint8_t eight[] = {0x00, 0x11, 0x22, 0x33, 0x44, 0x55, 0x66, 0x77};
    static const uint8_t lower[] = {0xDE, 0xAD, 0xBE, 0xEF, 0xCA, 0xFE, 0xBA, 0xBE};
    static const uint8_t mixed[] = {0xAB};
    open_rx_text(&hal, "valid.log",
                 "(1436509052.249713) vcan0 123#DEADBEEF\n"      /* std, dlc 4 */
                 "(1436509052.249714) vcan0 12345678#\n"         /* ext, dlc 0 */
                 "(1436509052.249715) can1 7FF#0011223344556677\n" /* max std, dlc 8 */
                 "(1436509052.249716) can1 1abcdef0#deadbeefcafebabe\n" /* lower case */
                 "(1436509052.249717) can1 000#\n"               /* std id 0, dlc 0 */
                 "(1436509052.249718) c 1FFFFFFF#aB\n"           /* max ext, mixed case */
                 "(1436509052.249719)\tcan0\t\t7ff#00  \r\n"     /* tabs, CRLF */
                 "(1436509052.249720) vcan0 123#DEADBEEF R\n"    /* python-can direction */
                 "(1436509052.249721) vcan0 123#DEADBEEF  T\n"
                 "(0000000001.500000) can0 00000000#0011223344556677"); /* no newline */
    expect_frame(&hal, 0x123, 0, 4, dead, UINT64_C(1436509052249713));
    expect_frame(&hal, 0x12345678, 1, 0, NULL, UINT64_C(1436509052249714));
    expect_frame(&hal, 0x7FF, 0, 8, eight, UINT64_C(1436509052249715));
    expect_frame(&hal, 0x1ABCDEF0, 1, 8, lower, UINT64_C(1436509052249716));
    expect_frame(&hal, 0x000, 0, 0, NULL, UINT64_C(1436509052249717));
    expect_frame(&hal, 0x1FFFFFFF, 1, 1, mixed, UINT64_C(1436509052249718));
    expect_frame(&hal, 0x7FF, 0, 1, eight, UINT64_C(1436509052249719));
    expect_frame(&hal, 0x123, 0, 4, dead, UINT64_C(1436509052249720));
    expect_frame(&hal, 0x123, 0, 4, dead, UINT64_C(1436509052249721));
    expect_frame(&hal, 0x00000000, 1, 8, eight, UINT64_C(1500000));
    expect_end(&hal);
    assert_int_equal(hal_can_rx_lost(&hal), 0);
    assert_int_equal(hal_linux_rx_frames(&hal), 10);
    assert_int_equal(hal_faults(&hal), 0u); /* a log: no watchdog to fail, no bus-off */
    /* what a live socket counts (hal_socketcan.c): two bus-off error frames are one event,
     * cleared by reading; its drops and the controller's overflows are frames lost */
    hal.can_bus_off = 2u;
    assert_int_equal(hal_faults(&hal), HAL_FAULT_BUS_OFF);
    assert_int_equal(hal_faults(&hal), 0u);
    hal.can_rx_dropped = 5u;
    hal.can_rx_overflow = 1u;
    assert_int_equal(hal_can_rx_lost(&hal), 6u);
    hal_linux_close(&hal);
}

/* a 15-character interface is the longest accepted */
static void test_rx_iface_length(void **state)
{
    (void)state;
    static hal_t hal;
    open_rx_text(&hal, "iface.log",
                 "(1.000000) abcdefghijklmno 123#\n"
                 "(2.000000) abcdefghijklmnop 123#\n"
                 "(3.000000) x 124#\n");
    expect_frame(&hal, 0x123, 0, 0, NULL, 1000000);
    expect_frame(&hal, 0x124, 0, 0, NULL, 3000000);
    assert_int_equal(hal_can_rx_lost(&hal), 1);
    expect_end(&hal);
    hal_linux_close(&hal);
}

/* ---- RX: timestamps ---- */

static void test_rx_timestamps_exact(void **state)
{
    (void)state;
    static hal_t hal;
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, NULL), 0);
    assert_true(hal_time_us(&hal) == 0);
    hal_linux_close(&hal);

    open_rx_text(&hal, "ts.log",
                 "(0.1) a 001#\n"                       /* 1 digit: 100000 us */
                 "(0.12) a 001#\n"
                 "(0.123) a 001#\n"
                 "(0.1234) a 001#\n"
                 "(0.12345) a 001#\n"
                 "(7.000001) a 001#\n"                  /* 1 us */
                 "(2.1234567) a 001#\n"                 /* 7 digits: truncated */
                 "(3.99999999) a 001#\n"
                 "(3.999999999) a 001#\n"               /* 9: truncated, not rounded */
                 "(0.0) a 001#\n"                       /* backwards: passed through */
                 "(0000000000.000000) a 001#\n"
                 "(1700000000.123456) a 001#\n"         /* beyond float32/double-safe use */
                 "(18446744073709.551615) a 001#\n");   /* UINT64_MAX us exactly */
    static const uint64_t want[] = {
        100000u, 120000u, 123000u, 123400u, 123450u, 7000001u, 2123456u, 3999999u, 3999999u,
        0u, 0u, UINT64_C(1700000000123456), UINT64_MAX};
    for (size_t k = 0; k < sizeof want / sizeof want[0]; k++) {
        expect_frame(&hal, 0x001, 0, 0, NULL, want[k]);
    }
    expect_end(&hal);
    assert_int_equal(hal_can_rx_lost(&hal), 0);
    /* the clock keeps the last frame's time after the end */
    assert_true(hal_time_us(&hal) == UINT64_MAX);
    hal_linux_close(&hal);
}

/* ---- RX: malformed lines, each counted once, the next good line still received ---- */

static const char *const malformed[] = {
    "garbage",
    "hello world 123#00",
    "1.000000) vcan0 123#00",               /* missing ( */
    "(1.000000 vcan0 123#00",               /* missing ) */
    "((1.000000) vcan0 123#00",             /* unbalanced */
    "(1.000000)) vcan0 123#00",
    "()) vcan0 123#00",
    "(1.000000) 123#00",                    /* missing interface */
    "(1.000000)  123#00 ",
    "(1.000000) vcan0",                     /* missing frame */
    "(1.000000) vcan0 ",
    "(1.000000)",
    "(1.000000)vcan0 123#00",               /* no blank after ) */
    "vcan0 123#00",                         /* missing timestamp */
    "(1.000000) vcan0 123#00 X",            /* extra field (only R or T may follow) */
    "(1.000000) vcan0 123#00 R R",
    "(1.000000) vcan0 123#00 RT",
    "(1.000000) vcan0 123#00 123#00",
    "(1.000000) vcan0 12G#00",              /* bad hex in ID */
    "(1.000000) vcan0 123#0G",              /* bad hex in data */
    "(1.000000) vcan0 123#-1",
    "(1.000000) vcan0 123# 00",
    "(1.000000) vcan0 123#11.22",           /* separators are not candump log format */
    "(1.000000) vcan0 123#ABC",             /* odd number of data digits */
    "(1.000000) vcan0 123#A",
    "(1.000000) vcan0 123#001122334455667788", /* 9 data bytes */
    "(1.000000) vcan0 800#00",              /* 3 digits wider than 11 bits */
    "(1.000000) vcan0 FFF#00",
    "(1.000000) vcan0 20000000#00",         /* 8 digits wider than 29 bits */
    "(1.000000) vcan0 FFFFFFFF#00",
    "(1.000000) vcan0 20000004#0000000000000000", /* error frame (CAN_ERR_FLAG) */
    "(1.000000) vcan0 #00",                 /* ID digit counts other than 3 and 8 */
    "(1.000000) vcan0 1#00",
    "(1.000000) vcan0 12#00",
    "(1.000000) vcan0 1234#00",
    "(1.000000) vcan0 0123#00",             /* in range, but 4 digits */
    "(1.000000) vcan0 01#00",
    "(1.000000) vcan0 0000123#00",
    "(1.000000) vcan0 1234567#00",
    "(1.000000) vcan0 123456789#00",
    "(1.000000) vcan0 0000000000000123#00",
    "(1.000000) vcan0 12300",               /* no # */
    "(1.000000) vcan0 123#R",               /* remote frames */
    "(1.000000) vcan0 123#R5",
    "(1.000000) vcan0 12345678#r",
    "(1.000000) vcan0 123##0112233",        /* CAN FD */
    "(1.000000) vcan0 123##1",
    "(1.000000) vcan0 123##",
    "(1.) vcan0 123#00",                    /* timestamp forms */
    "(.5) vcan0 123#00",
    "(1) vcan0 123#00",
    "() vcan0 123#00",
    "(-1.000000) vcan0 123#00",
    "(+1.000000) vcan0 123#00",
    "(1,000000) vcan0 123#00",
    "(1.0000000000) vcan0 123#00",          /* 10 fraction digits */
    "(1.000 000) vcan0 123#00",
    "( 1.000000) vcan0 123#00",
    "(0x1.000000) vcan0 123#00",
    "(18446744073709.551616) vcan0 123#00", /* one past UINT64_MAX us */
    "(18446744073710.000000) vcan0 123#00",
    "(99999999999999999999.000000) vcan0 123#00", /* seconds overflow uint64 */
    "(1.000000) vcan\x01 123#00",           /* control character in the interface */
    "(1.000000) vcan0 123#00\x7f",
};

static void test_rx_malformed_each(void **state)
{
    (void)state;
    static hal_t hal;
    static const uint8_t good_data[] = {0x42};
    char text[256];
    for (size_t k = 0; k < sizeof malformed / sizeof malformed[0]; k++) {
        const int n = snprintf(text, sizeof text, "%s\n(5.000000) can0 321#42\n", malformed[k]);
        assert_true(n > 0 && (size_t)n < sizeof text);
        open_rx_text(&hal, "bad.log", text);
        hal_can_frame_t f;
        memset(&f, 0, sizeof f);
        const int rc = hal_can_receive(&hal, &f);
        if (rc != 0 || f.id != 0x321 || hal_can_rx_lost(&hal) != 1) {
            fail_msg("case %zu \"%s\": rc %d id 0x%X malformed %u", k, malformed[k], rc,
                     (unsigned)f.id, (unsigned)hal_can_rx_lost(&hal));
        }
        assert_int_equal(f.dlc, 1);
        assert_memory_equal(f.data, good_data, 1);
        assert_true(f.t_us == 5000000u);
        expect_end(&hal);
        assert_int_equal(hal_can_rx_lost(&hal), 1);
        hal_linux_close(&hal);

        /* the same as the last line, without newline: counted once, then the end */
        open_rx_text(&hal, "bad_last.log", malformed[k]);
        expect_end(&hal);
        assert_int_equal(hal_can_rx_lost(&hal), 1);
        hal_linux_close(&hal);
    }
}

/* NUL and high bytes inside a line */
static void test_rx_malformed_binary(void **state)
{
    (void)state;
    static hal_t hal;
    static const char text[] = "(1.000000) vcan0 123#00\0\n"
                               "(1.000000) vc\0n0 123#00\n"
                               "(1.000000) vcan0 1\x80" "3#00\n"
                               "\xff\xfe\n"
                               "(2.000000) vcan0 321#42\n";
    char p[PATH_LEN];
    write_file_n(p, "binary.log", text, sizeof text - 1);
    assert_int_equal(hal_linux_open(&hal, p, NULL, NULL), 0);
    static const uint8_t d[] = {0x42};
    expect_frame(&hal, 0x321, 0, 1, d, 2000000);
    assert_int_equal(hal_can_rx_lost(&hal), 4);
    expect_end(&hal);
    hal_linux_close(&hal);
}

/* line length: HAL_LINUX_LINE_MAX characters fit, one more is over-long (counted once,
 * the rest of the line dropped, the next line read normally) */
static void test_rx_overlong(void **state)
{
    (void)state;
    static hal_t hal;
    static char text[4096];
    char line[1024];
    const char *head = "(1.000000) vcan0 123#00";
    const size_t head_len = strlen(head);
    size_t len = 0;

    /* exactly HAL_LINUX_LINE_MAX characters: valid (padded with trailing blanks) */
    memset(line, ' ', HAL_LINUX_LINE_MAX);
    memcpy(line, head, head_len);
    memcpy(text + len, line, HAL_LINUX_LINE_MAX);
    len += HAL_LINUX_LINE_MAX;
    text[len++] = '\n';
    /* one character more: over-long although it would parse */
    memset(line, ' ', HAL_LINUX_LINE_MAX + 1);
    memcpy(line, head, head_len);
    memcpy(text + len, line, HAL_LINUX_LINE_MAX + 1);
    len += HAL_LINUX_LINE_MAX + 1;
    text[len++] = '\n';
    /* far over-long, a good line hidden past the buffer must not be seen */
    memset(text + len, 'A', 700);
    len += 700;
    memcpy(text + len, "(3.000000) vcan0 333#33", 23); /* same line: dropped with it */
    len += 23;
    text[len++] = '\n';
    const char *good = "(2.000000) vcan0 222#22\n";
    memcpy(text + len, good, strlen(good));
    len += strlen(good);
    /* over-long final line without newline */
    memset(text + len, 'B', 300);
    len += 300;

    char p[PATH_LEN];
    write_file_n(p, "long.log", text, len);
    assert_int_equal(hal_linux_open(&hal, p, NULL, NULL), 0);
    static const uint8_t d0[] = {0x00};
    static const uint8_t d22[] = {0x22};
    expect_frame(&hal, 0x123, 0, 1, d0, 1000000);
    assert_int_equal(hal_can_rx_lost(&hal), 0);
    expect_frame(&hal, 0x222, 0, 1, d22, 2000000);
    assert_int_equal(hal_can_rx_lost(&hal), 2);
    expect_end(&hal);
    assert_int_equal(hal_can_rx_lost(&hal), 3);
    hal_linux_close(&hal);
}

static void test_rx_blank_lines_not_counted(void **state)
{
    (void)state;
    static hal_t hal;
    open_rx_text(&hal, "blank.log",
                 "\n\n   \n\t\n\r\n"
                 "(1.000000) vcan0 123#\n"
                 "\n"
                 " \t ");
    expect_frame(&hal, 0x123, 0, 0, NULL, 1000000);
    expect_end(&hal);
    assert_int_equal(hal_can_rx_lost(&hal), 0);
    hal_linux_close(&hal);
}

static void test_rx_end_of_file(void **state)
{
    (void)state;
    static hal_t hal;
    open_rx_text(&hal, "empty.log", "");
    expect_end(&hal);
    hal_linux_close(&hal);

    /* no RX log at all */
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, NULL), 0);
    expect_end(&hal);
    hal_linux_close(&hal);

    /* a missing RX log is an open error */
    char p[PATH_LEN];
    tmp_path(p, "does_not_exist.log");
    assert_int_equal(hal_linux_open(&hal, p, NULL, NULL), HAL_EIO);
    assert_int_equal(hal_linux_open_failed(&hal), HAL_LINUX_FILE_RX); /* for the message */
    hal_linux_close(&hal); /* harmless after a failed open */

    /* after the last frame, and many calls after that */
    open_rx_text(&hal, "one.log", "(1.000000) vcan0 123#\n");
    expect_frame(&hal, 0x123, 0, 0, NULL, 1000000);
    for (int k = 0; k < 10; k++) {
        expect_end(&hal);
    }
    hal_linux_close(&hal);
    hal_linux_close(&hal); /* twice is harmless */
}

/* ---- TX ---- */

static void test_tx_format(void **state)
{
    (void)state;
    static hal_t hal;
    char rx[PATH_LEN], tx[PATH_LEN], out[1024];
    write_file(rx, "tx_in.log", "(1436509052.249713) vcan0 7FF#\n(0000000042.000007) x 001#\n");
    write_file(tx, "tx_out.log", "old contents, truncated on open\n");
    assert_int_equal(hal_linux_open(&hal, rx, tx, NULL), 0);

    const hal_can_frame_t std = {.id = 0x123, .extended = 0, .dlc = 4,
                                 .data = {0xDE, 0xAD, 0xBE, 0xEF}};
    const hal_can_frame_t ext = {.id = 0x1ABCDEF0, .extended = 1, .dlc = 8,
                                 .data = {0x01, 0x23, 0x45, 0x67, 0x89, 0xab, 0xcd, 0xef}};
    const hal_can_frame_t empty = {.id = 0x5, .extended = 1, .dlc = 0};
    /* before any RX: time 0, default interface */
    assert_int_equal(hal_can_send(&hal, &std), 0);
    hal_can_frame_t f;
    assert_int_equal(hal_can_receive(&hal, &f), 0);
    hal_linux_set_iface(&hal, "vcan1");
    assert_int_equal(hal_can_send(&hal, &std), 0);
    assert_int_equal(hal_can_send(&hal, &ext), 0);
    assert_int_equal(hal_can_receive(&hal, &f), 0);
    hal_linux_set_iface(&hal, "a b\tcdefghijklmnopqrstuvwxyz"); /* cut to 15, blanks to _ */
    assert_int_equal(hal_can_send(&hal, &empty), 0);
    hal_linux_set_iface(&hal, NULL);
    assert_int_equal(hal_can_send(&hal, &std), 0);
    assert_int_equal(hal_linux_tx_frames(&hal), 5);
    hal_linux_close(&hal);

    read_file(tx, out, sizeof out);
    assert_string_equal(out,
                        "(0000000000.000000) can0 123#DEADBEEF\n"
                        "(1436509052.249713) vcan1 123#DEADBEEF\n"
                        "(1436509052.249713) vcan1 1ABCDEF0#0123456789ABCDEF\n"
                        "(0000000042.000007) a_b_cdefghijklm 00000005#\n"
                        "(0000000042.000007) can0 123#DEADBEEF\n");

    /* the TX log replays as an RX log, frame for frame */
    assert_int_equal(hal_linux_open(&hal, tx, NULL, NULL), 0);
    expect_frame(&hal, 0x123, 0, 4, std.data, 0);
    expect_frame(&hal, 0x123, 0, 4, std.data, UINT64_C(1436509052249713));
    expect_frame(&hal, 0x1ABCDEF0, 1, 8, ext.data, UINT64_C(1436509052249713));
    expect_frame(&hal, 0x5, 1, 0, NULL, 42000007);
    expect_frame(&hal, 0x123, 0, 4, std.data, 42000007);
    expect_end(&hal);
    assert_int_equal(hal_can_rx_lost(&hal), 0);
    hal_linux_close(&hal);
}

static void test_tx_rejects_bad_frames(void **state)
{
    (void)state;
    static hal_t hal;
    char tx[PATH_LEN], out[256];
    tmp_path(tx, "tx_bad.log");
    assert_int_equal(hal_linux_open(&hal, NULL, tx, NULL), 0);
    hal_can_frame_t f = {.id = 0x123, .extended = 0, .dlc = 9};
    assert_int_equal(hal_can_send(&hal, &f), HAL_EINVAL);
    f.dlc = 255;
    assert_int_equal(hal_can_send(&hal, &f), HAL_EINVAL);
    f.dlc = 0;
    f.id = 0x800; /* wider than 11 bits */
    assert_int_equal(hal_can_send(&hal, &f), HAL_EINVAL);
    f.extended = 1;
    f.id = 0x20000000; /* wider than 29 bits */
    assert_int_equal(hal_can_send(&hal, &f), HAL_EINVAL);
    f.extended = 2;
    f.id = 0x1;
    assert_int_equal(hal_can_send(&hal, &f), HAL_EINVAL);
    assert_int_equal(hal_can_send(&hal, NULL), HAL_EINVAL);
    f.extended = 0;
    f.dlc = 8; /* the largest accepted */
    assert_int_equal(hal_can_send(&hal, &f), 0);
    assert_int_equal(hal_linux_tx_frames(&hal), 1);
    hal_linux_close(&hal);
    read_file(tx, out, sizeof out);
    assert_string_equal(out, "(0000000000.000000) can0 001#0000000000000000\n");
}

/* no TX log: frames are checked, then dropped */
static void test_tx_discard(void **state)
{
    (void)state;
    static hal_t hal;
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, NULL), 0);
    const hal_can_frame_t f = {.id = 0x1, .dlc = 1};
    const hal_can_frame_t bad = {.id = 0x1, .dlc = 9};
    assert_int_equal(hal_can_send(&hal, &f), 0);
    assert_int_equal(hal_can_send(&hal, &bad), HAL_EINVAL);
    assert_int_equal(hal_linux_tx_frames(&hal), 1);
    hal_linux_close(&hal);
}

/* a write error is reported (/dev/full accepts open and fails every write) */
static void test_tx_write_error(void **state)
{
    (void)state;
    static hal_t hal;
    if (access("/dev/full", W_OK) != 0) {
        skip();
    }
    assert_int_equal(hal_linux_open(&hal, NULL, "/dev/full", NULL), 0);
    const hal_can_frame_t f = {.id = 0x1, .dlc = 8};
    int rc = 0;
    /* buffered: the error shows once the stdio buffer is flushed */
    for (int k = 0; k < 100000 && rc == 0; k++) {
        rc = hal_can_send(&hal, &f);
    }
    assert_int_equal(rc, HAL_EIO);
    assert_int_equal(hal_can_send(&hal, &f), HAL_EIO); /* and stays reported */
    hal_linux_close(&hal);
}

/* ---- NVM ---- */

static void expect_nvm_all(hal_t *hal, uint8_t v)
{
    static uint8_t buf[HAL_LINUX_NVM_SIZE], want[HAL_LINUX_NVM_SIZE];
    memset(want, v, sizeof want);
    assert_int_equal(hal_nvm_read(hal, 0, buf, sizeof buf), 0);
    assert_memory_equal(buf, want, sizeof want);
}

static void test_nvm_memory(void **state)
{
    (void)state;
    static hal_t hal;
    uint8_t buf[16];
    static const uint8_t pattern[] = {1, 2, 3, 4, 5};
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, NULL), 0);
    assert_int_equal(hal_nvm_size(&hal), 4096);
    expect_nvm_all(&hal, 0xFF);

    assert_int_equal(hal_nvm_write(&hal, 100, pattern, sizeof pattern), 0);
    memset(buf, 0, sizeof buf);
    assert_int_equal(hal_nvm_read(&hal, 99, buf, 7), 0);
    static const uint8_t want[] = {0xFF, 1, 2, 3, 4, 5, 0xFF};
    assert_memory_equal(buf, want, sizeof want);
    /* the last bytes of the region */
    assert_int_equal(hal_nvm_write(&hal, 4096 - 5, pattern, 5), 0);
    assert_int_equal(hal_nvm_read(&hal, 4096 - 5, buf, 5), 0);
    assert_memory_equal(buf, pattern, 5);

    assert_int_equal(hal_nvm_erase(&hal), 0);
    expect_nvm_all(&hal, 0xFF);
    hal_linux_close(&hal);
}

static void test_nvm_bounds(void **state)
{
    (void)state;
    static hal_t hal;
    uint8_t buf[8] = {0};
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, NULL), 0);
    /* empty ranges up to and at the end are fine */
    assert_int_equal(hal_nvm_read(&hal, 4096, buf, 0), 0);
    assert_int_equal(hal_nvm_write(&hal, 4096, buf, 0), 0);
    assert_int_equal(hal_nvm_read(&hal, 0, NULL, 0), 0);
    assert_int_equal(hal_nvm_read(&hal, 4095, buf, 1), 0);
    /* past the end */
    assert_int_equal(hal_nvm_read(&hal, 4096, buf, 1), HAL_EINVAL);
    assert_int_equal(hal_nvm_write(&hal, 4096, buf, 1), HAL_EINVAL);
    assert_int_equal(hal_nvm_read(&hal, 4095, buf, 2), HAL_EINVAL);
    assert_int_equal(hal_nvm_write(&hal, 4095, buf, 2), HAL_EINVAL);
    assert_int_equal(hal_nvm_read(&hal, 4097, buf, 0), HAL_EINVAL);
    /* offset + len would wrap around */
    assert_int_equal(hal_nvm_read(&hal, SIZE_MAX, buf, 2), HAL_EINVAL);
    assert_int_equal(hal_nvm_write(&hal, SIZE_MAX, buf, 2), HAL_EINVAL);
    assert_int_equal(hal_nvm_read(&hal, 1, buf, SIZE_MAX), HAL_EINVAL);
    assert_int_equal(hal_nvm_write(&hal, 1, buf, SIZE_MAX), HAL_EINVAL);
    assert_int_equal(hal_nvm_read(&hal, 0, NULL, 1), HAL_EINVAL);
    assert_int_equal(hal_nvm_write(&hal, 0, NULL, 1), HAL_EINVAL);
    /* a rejected write changes nothing */
    expect_nvm_all(&hal, 0xFF);
    hal_linux_close(&hal);
}

static void test_nvm_persistence(void **state)
{
    (void)state;
    static hal_t hal;
    static char image[HAL_LINUX_NVM_SIZE + 16];
    char nvm[PATH_LEN];
    tmp_path(nvm, "nvm.bin");
    (void)unlink(nvm);

    /* GIVEN no file WHEN opened THEN it is created: 4096 bytes of 0xFF */
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, nvm), 0);
    expect_nvm_all(&hal, 0xFF);
    assert_int_equal(read_file(nvm, image, sizeof image), HAL_LINUX_NVM_SIZE);
    for (size_t k = 0; k < HAL_LINUX_NVM_SIZE; k++) {
        assert_int_equal((uint8_t)image[k], 0xFF);
    }
    static const uint8_t rec[] = {0x10, 0x20, 0x30, 0x40};
    assert_int_equal(hal_nvm_erase(&hal), 0);
    assert_int_equal(hal_nvm_write(&hal, 2000, rec, sizeof rec), 0);
    /* write-through: the file has it before close */
    assert_int_equal(read_file(nvm, image, sizeof image), HAL_LINUX_NVM_SIZE);
    assert_memory_equal(image + 2000, rec, sizeof rec);
    hal_linux_close(&hal);

    /* reopened: the data is back */
    uint8_t buf[8];
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, nvm), 0);
    assert_int_equal(hal_nvm_read(&hal, 1999, buf, 6), 0);
    static const uint8_t want[] = {0xFF, 0x10, 0x20, 0x30, 0x40, 0xFF};
    assert_memory_equal(buf, want, sizeof want);
    assert_int_equal(hal_nvm_erase(&hal), 0);
    hal_linux_close(&hal);

    /* the erase persisted too */
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, nvm), 0);
    expect_nvm_all(&hal, 0xFF);
    hal_linux_close(&hal);
    assert_int_equal(read_file(nvm, image, sizeof image), HAL_LINUX_NVM_SIZE);

    /* a file of another size is not an NVM image: open fails, nothing left open */
    char bad[PATH_LEN];
    write_file(bad, "nvm_short.bin", "short");
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, bad), HAL_EIO);
    assert_int_equal(hal_linux_open_failed(&hal), HAL_LINUX_FILE_NVM_SIZE);
    hal_linux_close(&hal);
    memset(image, 0, sizeof image);
    write_file_n(bad, "nvm_long.bin", image, HAL_LINUX_NVM_SIZE + 1);
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, bad), HAL_EIO);
    assert_int_equal(hal_linux_open_failed(&hal), HAL_LINUX_FILE_NVM_SIZE);
    hal_linux_close(&hal);
    /* a path in a missing directory cannot be created */
    tmp_path(bad, "no_such_dir/nvm.bin");
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, bad), HAL_EIO);
    assert_int_equal(hal_linux_open_failed(&hal), HAL_LINUX_FILE_NVM);
    hal_linux_close(&hal);
    /* an output log in a missing directory: the output log is named, not the NVM */
    assert_int_equal(hal_linux_open(&hal, NULL, bad, nvm), HAL_EIO);
    assert_int_equal(hal_linux_open_failed(&hal), HAL_LINUX_FILE_TX);
    hal_linux_close(&hal);
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, nvm), 0);
    assert_int_equal(hal_linux_open_failed(&hal), HAL_LINUX_FILE_NONE);
    hal_linux_close(&hal);
}

/*
 * Flash semantics (hal.h): 2 sectors of 2048 bytes; a write stores old AND new and reports
 * HAL_EIO when a bit would have to go from 0 to 1; one sector erases alone; the file
 * follows.
 */
static void test_nvm_flash_semantics(void **state)
{
    (void)state;
    static hal_t hal;
    static char image[HAL_LINUX_NVM_SIZE + 16];
    char nvm[PATH_LEN];
    uint8_t b[4];
    tmp_path(nvm, "nvm_flash.bin");
    (void)unlink(nvm);
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, nvm), 0);
    assert_int_equal(hal_nvm_sector_size(&hal), 2048);
    assert_int_equal(hal_nvm_size(&hal) / hal_nvm_sector_size(&hal), 2);

    static const uint8_t first[] = {0xF0, 0x0F, 0xAA, 0x00};
    static const uint8_t clear_more[] = {0x30, 0x0F, 0x00, 0x00}; /* only clears bits */
    static const uint8_t set_bits[] = {0xFF, 0x3C, 0x55, 0x01};   /* needs 0 -> 1 */
    assert_int_equal(hal_nvm_write(&hal, 10, first, 4), 0);
    assert_int_equal(hal_nvm_write(&hal, 10, clear_more, 4), 0);
    assert_int_equal(hal_nvm_read(&hal, 10, b, 4), 0);
    assert_memory_equal(b, clear_more, 4);
    assert_int_equal(hal_nvm_write(&hal, 10, set_bits, 4), HAL_EIO);
    static const uint8_t anded[] = {0x30, 0x0C, 0x00, 0x00};
    assert_int_equal(hal_nvm_read(&hal, 10, b, 4), 0);
    assert_memory_equal(b, anded, 4);
    assert_int_equal(read_file(nvm, image, sizeof image), HAL_LINUX_NVM_SIZE);
    assert_memory_equal(image + 10, anded, 4);

    /* sector 1 erases alone; sector 0 keeps its bytes, in memory and in the file */
    assert_int_equal(hal_nvm_write(&hal, 2048, first, 4), 0);
    assert_int_equal(hal_nvm_write(&hal, 4095, first, 1), 0);
    assert_int_equal(hal_nvm_erase_sector(&hal, 1), 0);
    assert_int_equal(hal_nvm_erase_sector(&hal, 2), HAL_EINVAL);
    assert_int_equal(hal_nvm_erase_sector(&hal, SIZE_MAX), HAL_EINVAL);
    assert_int_equal(hal_nvm_erase_sector(NULL, 0), HAL_EINVAL);
    assert_int_equal(hal_nvm_read(&hal, 10, b, 4), 0);
    assert_memory_equal(b, anded, 4);
    hal_linux_close(&hal);
    assert_int_equal(read_file(nvm, image, sizeof image), HAL_LINUX_NVM_SIZE);
    assert_memory_equal(image + 10, anded, 4);
    for (size_t k = 2048; k < HAL_LINUX_NVM_SIZE; k++) {
        assert_int_equal((uint8_t)image[k], 0xFF);
    }

    /* after reopening, the flash rule still holds against the file's contents */
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, nvm), 0);
    assert_int_equal(hal_nvm_write(&hal, 10, first, 1), HAL_EIO); /* 0x30 -> 0xF0 */
    assert_int_equal(hal_nvm_erase_sector(&hal, 0), 0);
    assert_int_equal(hal_nvm_write(&hal, 10, first, 4), 0);
    assert_int_equal(hal_nvm_read(&hal, 10, b, 4), 0);
    assert_memory_equal(b, first, 4);
    hal_linux_close(&hal);
}

/* ---- watchdog ---- */

static void test_watchdog_counts(void **state)
{
    (void)state;
    static hal_t hal;
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, NULL), 0);
    assert_int_equal(hal_linux_watchdog_kicks(&hal), 0);
    for (int k = 0; k < 3; k++) {
        hal_watchdog_kick(&hal);
    }
    assert_int_equal(hal_linux_watchdog_kicks(&hal), 3);
    hal_linux_close(&hal);
    assert_int_equal(hal_linux_open(&hal, NULL, NULL, NULL), 0);
    assert_int_equal(hal_linux_watchdog_kicks(&hal), 0); /* open resets it */
    hal_linux_close(&hal);
}

/* ---- fuzz-ish: 100 000 random lines ---- */

static uint64_t rng_state;

/* xorshift64*: deterministic for a seed, same on every platform */
static uint32_t rng_next(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (uint32_t)((rng_state * UINT64_C(2685821657736338717)) >> 32);
}

static uint32_t rng_below(uint32_t n)
{
    return rng_next() % n;
}

/*
 * GIVEN 100 000 lines: every eighth a known-good frame, the others random bytes,
 * random characters of the log alphabet, or good lines with a few characters changed,
 * cut, or repeated past the line buffer
 * WHEN replayed to the end
 * THEN nothing crashes, every known-good frame arrives in order, every frame returned is
 * a valid classic frame, and every non-blank line is either returned or counted.
 */
static void test_rx_fuzz(void **state)
{
    (void)state;
    static hal_t hal;
    enum { N_LINES = 100000 };
    static const char alphabet[] = "0123456789abcdefABCDEFRr#().  \t\rxvcan";
    char p[PATH_LEN];
    tmp_path(p, "fuzz.log");
    FILE *fp = fopen(p, "wb");
    assert_non_null(fp);
    rng_state = UINT64_C(0x9E3779B97F4A7C15);

    uint32_t n_good = 0;
    char line[512];
    for (uint32_t k = 0; k < N_LINES; k++) {
        size_t n = 0;
        if (k % 8u == 0u) {
            /* marker frame: ID 0x7E0 carries its own sequence number */
            const int w = snprintf(line, sizeof line, "(%u.%06u) can0 7E0#%08X\n",
                                   k / 8u, k % 1000000u, n_good);
            assert_true(w > 0);
            assert_int_equal(fwrite(line, 1, (size_t)w, fp), (size_t)w);
            n_good++;
            continue;
        }
        switch (rng_below(3)) {
        case 0: /* random bytes, newline excluded */
            n = rng_below(300);
            for (size_t j = 0; j < n; j++) {
                char c;
                do {
                    c = (char)(unsigned char)rng_below(256);
                } while (c == '\n');
                line[j] = c;
            }
            break;
        case 1: /* random characters of the log alphabet */
            n = rng_below(160);
            for (size_t j = 0; j < n; j++) {
                line[j] = alphabet[rng_below(sizeof alphabet - 1)];
            }
            break;
        default: { /* a plausible line, mutated */
            const uint32_t nd = rng_below(11);
            int w = snprintf(line, sizeof line, "(%u.%06u) vcan%u %0*X#", rng_next(),
                             rng_below(1000000), rng_below(10), rng_below(2) ? 3 : 8,
                             rng_next() & 0x3FFFFFFFu);
            assert_true(w > 0);
            n = (size_t)w;
            for (uint32_t j = 0; j < nd; j++) {
                n += (size_t)snprintf(line + n, sizeof line - n, "%02x", rng_below(256));
            }
            const uint32_t muts = rng_below(4);
            for (uint32_t j = 0; j < muts && n > 0; j++) {
                switch (rng_below(3)) {
                case 0:
                    line[rng_below((uint32_t)n)] = alphabet[rng_below(sizeof alphabet - 1)];
                    break;
                case 1:
                    n = rng_below((uint32_t)n); /* cut */
                    break;
                default:
                    while (n < 300) { /* pad past the line buffer */
                        line[n++] = ' ';
                    }
                    break;
                }
            }
            break;
        }
        }
        assert_int_equal(fwrite(line, 1, n, fp), n);
        assert_int_equal(fputc('\n', fp), '\n');
    }
    assert_int_equal(fclose(fp), 0);

    assert_int_equal(hal_linux_open(&hal, p, NULL, NULL), 0);
    hal_can_frame_t f;
    uint32_t n_rx = 0, n_marker = 0;
    int rc;
    while ((rc = hal_can_receive(&hal, &f)) == 0) {
        n_rx++;
        assert_true(f.dlc <= 8);
        assert_true(f.extended <= 1);
        assert_true(f.id <= (f.extended ? 0x1FFFFFFFu : 0x7FFu));
        assert_true(hal_time_us(&hal) == f.t_us);
        if (f.id == 0x7E0 && f.extended == 0 && f.dlc == 4) {
            const uint32_t seq = (uint32_t)f.data[0] << 24 | (uint32_t)f.data[1] << 16 |
                                 (uint32_t)f.data[2] << 8 | f.data[3];
            if (seq == n_marker) { /* random lines may fake a marker; real ones in order */
                n_marker++;
            }
        }
    }
    assert_int_equal(rc, HAL_ENODATA);
    assert_int_equal(n_marker, n_good);
    assert_true(n_rx >= n_good);
    assert_true((uint64_t)n_rx + hal_can_rx_lost(&hal) <= N_LINES);
    /* nearly every random line is malformed rather than blank */
    assert_true(hal_can_rx_lost(&hal) > N_LINES / 2);
    print_message("fuzz: %u lines, %u frames, %u malformed\n", (unsigned)N_LINES,
                  (unsigned)n_rx, (unsigned)hal_can_rx_lost(&hal));
    hal_linux_close(&hal);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rx_valid_forms),
        cmocka_unit_test(test_rx_iface_length),
        cmocka_unit_test(test_rx_timestamps_exact),
        cmocka_unit_test(test_rx_malformed_each),
        cmocka_unit_test(test_rx_malformed_binary),
        cmocka_unit_test(test_rx_overlong),
        cmocka_unit_test(test_rx_blank_lines_not_counted),
        cmocka_unit_test(test_rx_end_of_file),
        cmocka_unit_test(test_tx_format),
        cmocka_unit_test(test_tx_rejects_bad_frames),
        cmocka_unit_test(test_tx_discard),
        cmocka_unit_test(test_tx_write_error),
        cmocka_unit_test(test_nvm_memory),
        cmocka_unit_test(test_nvm_bounds),
        cmocka_unit_test(test_nvm_persistence),
        cmocka_unit_test(test_nvm_flash_semantics),
        cmocka_unit_test(test_watchdog_counts),
        cmocka_unit_test(test_rx_fuzz),
    };
    return cmocka_run_group_tests_name("hal_linux", tests, group_setup, group_teardown);
}
