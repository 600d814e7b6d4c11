/*
 * fuzz_candump.c - libFuzzer harness: the host's candump log reader.
 *
 * The input is used three ways:
 *  1. as one line: candump_parse_line (hal/common/candump.h) on all of it;
 *  2. as a whole log file: written to a memfd, opened with hal_linux_open and read with
 *     hal_can_receive until HAL_ENODATA (hal/linux/hal_linux.h);
 *  3. its first 21 bytes as a frame (id, extended, dlc, data, time) for
 *     candump_format_line.
 *
 * Invariants (abort on violation):
 *  - a parsed frame is a classic frame: dlc <= 8, extended 0 or 1, id <= 0x7FF (standard)
 *    or <= 0x1FFFFFFF (extended), the unused data bytes 0; candump_format_line of it
 *    parses back to the same frame and time; a line that is not a frame leaves *f as it
 *    was; CANDUMP_BLANK exactly for lines of only blanks (space, tab, CR);
 *  - the log reader returns exactly the frames a reference splitter finds (the input cut
 *    at each '\n', a last line without newline included, lines over HAL_LINUX_LINE_MAX
 *    characters malformed, each line through candump_parse_line), in order, with
 *    hal_time_us() the frame's time; hal_can_rx_lost() and hal_linux_rx_frames()
 *    count what the reference counts; HAL_ENODATA at the end and after it;
 *  - candump_format_line writes what parses back to the same frame, and returns 0 for a
 *    frame a classic bus cannot carry.
 */
#define _GNU_SOURCE /* memfd_create */
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "candump.h"
#include "fuzz_fail.h"
#include "hal_linux.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static hal_t hal;

static int same_frame(const hal_can_frame_t *a, const hal_can_frame_t *b)
{
    return a->id == b->id && a->extended == b->extended && a->dlc == b->dlc && a->t_us == b->t_us &&
           memcmp(a->data, b->data, 8u) == 0;
}

static int all_blank(const char *s, size_t n)
{
    for (size_t k = 0u; k < n; k++) {
        if (s[k] != ' ' && s[k] != '\t' && s[k] != '\r') {
            return 0;
        }
    }
    return 1;
}

/* the classic-frame invariants and the format/parse round trip */
static void check_frame(const hal_can_frame_t *f, const char *where)
{
    if (f->dlc > 8u || f->extended > 1u || f->id > (f->extended ? 0x1FFFFFFFu : 0x7FFu)) {
        fuzz_fail("%s: frame id 0x%X ext %u dlc %u is not a classic frame", where, (unsigned)f->id,
                  f->extended, f->dlc);
    }
    for (unsigned k = f->dlc; k < 8u; k++) {
        if (f->data[k] != 0u) {
            fuzz_fail("%s: data byte %u beyond dlc %u is 0x%02X, not 0", where, k, f->dlc, f->data[k]);
        }
    }
    char buf[CANDUMP_FORMAT_MAX];
    const size_t n = candump_format_line(buf, sizeof buf, f->t_us, "can0", f);
    if (n == 0u || buf[n - 1u] != '\n') {
        fuzz_fail("%s: candump_format_line refused a parsed frame", where);
    }
    hal_can_frame_t g;
    memset(&g, 0, sizeof g);
    if (candump_parse_line(buf, n - 1u, &g) != CANDUMP_FRAME || !same_frame(f, &g)) {
        fuzz_fail("%s: '%.*s' does not parse back to the same frame", where, (int)(n - 1u), buf);
    }
}

/* 1: the input as one line */
static candump_line_t parse_checked(const char *s, size_t n, hal_can_frame_t *f)
{
    hal_can_frame_t before;
    memset(&before, 0xA5, sizeof before);
    *f = before;
    const candump_line_t r = candump_parse_line(s, n, f);
    if (r == CANDUMP_FRAME) {
        check_frame(f, "candump_parse_line");
    } else if (memcmp(f, &before, sizeof before) != 0) {
        fuzz_fail("candump_parse_line changed *f on a line that is not a frame");
    }
    if ((r == CANDUMP_BLANK) != all_blank(s, n)) {
        fuzz_fail("candump_parse_line: %s for a line %s only blanks",
                  r == CANDUMP_BLANK ? "CANDUMP_BLANK" : "not CANDUMP_BLANK",
                  all_blank(s, n) ? "of" : "not of");
    }
    return r;
}

/* 2: the input as a log file, against the reference splitter */
static void check_reader(const uint8_t *data, size_t size)
{
    const int fd = memfd_create("fuzz_candump", 0u);
    if (fd < 0) {
        return;
    }
    if (size > 0u && write(fd, data, size) != (ssize_t)size) {
        close(fd);
        return;
    }
    char path[64];
    (void)snprintf(path, sizeof path, "/proc/self/fd/%d", fd);
    if (hal_linux_open(&hal, path, NULL, NULL) != 0) {
        close(fd);
        fuzz_fail("hal_linux_open of a readable log failed");
    }
    uint32_t ref_frames = 0u, ref_malformed = 0u;
    size_t start = 0u;
    while (start < size) {
        const uint8_t *nl = memchr(data + start, '\n', size - start);
        const size_t end = nl != NULL ? (size_t)(nl - data) : size;
        const char *line = (const char *)data + start;
        const size_t len = end - start;
        start = end + 1u;
        hal_can_frame_t want;
        if (len > HAL_LINUX_LINE_MAX) {
            ref_malformed++;
            continue;
        }
        const candump_line_t r = parse_checked(line, len, &want);
        if (r == CANDUMP_MALFORMED) {
            ref_malformed++;
            continue;
        }
        if (r != CANDUMP_FRAME) {
            continue;
        }
        ref_frames++;
        hal_can_frame_t got;
        memset(&got, 0, sizeof got);
        const int rc = hal_can_receive(&hal, &got);
        if (rc != 0 || !same_frame(&got, &want)) {
            fuzz_fail("hal_can_receive: frame %u: rc %d%s", ref_frames, rc,
                      rc == 0 ? ", not the frame of its line" : "");
        }
        if (hal_time_us(&hal) != want.t_us) {
            fuzz_fail("hal_time_us is not the time of the last frame received");
        }
    }
    hal_can_frame_t f;
    for (int k = 0; k < 2; k++) {
        const int rc = hal_can_receive(&hal, &f);
        if (rc != HAL_ENODATA) {
            fuzz_fail("hal_can_receive after %u frames: %d, not HAL_ENODATA", ref_frames, rc);
        }
    }
    if (hal_can_rx_lost(&hal) != ref_malformed || hal_linux_rx_frames(&hal) != ref_frames) {
        fuzz_fail("log reader counted %u malformed lines and %u frames, the reference %u and %u",
                  hal_can_rx_lost(&hal), hal_linux_rx_frames(&hal), ref_malformed, ref_frames);
    }
    hal_linux_close(&hal);
    close(fd);
}

/* 3: candump_format_line on an arbitrary frame */
static void check_format(const uint8_t *data, size_t size)
{
    if (size < 21u) {
        return;
    }
    hal_can_frame_t f;
    memset(&f, 0, sizeof f);
    f.id = (uint32_t)data[0] | (uint32_t)data[1] << 8 | (uint32_t)data[2] << 16 | (uint32_t)data[3] << 24;
    f.extended = data[4];
    f.dlc = data[5];
    memcpy(f.data, data + 6, 8u);
    uint64_t t = 0u;
    for (int k = 0; k < 7; k++) {
        t |= (uint64_t)data[14 + k] << (8 * k);
    }
    t |= (uint64_t)(data[0] & 0x80u) << 49; /* times beyond 2^56 us too */
    f.t_us = t;
    char buf[CANDUMP_FORMAT_MAX];
    const size_t n = candump_format_line(buf, sizeof buf, f.t_us, "vcan0", &f);
    const int classic = f.dlc <= 8u && f.extended <= 1u && f.id <= (f.extended ? 0x1FFFFFFFu : 0x7FFu);
    if (!classic) {
        if (n != 0u) {
            fuzz_fail("candump_format_line wrote a frame a classic bus cannot carry");
        }
        return;
    }
    if (n == 0u) {
        fuzz_fail("candump_format_line refused a classic frame");
    }
    for (unsigned k = f.dlc; k < 8u; k++) {
        f.data[k] = 0u; /* not written: they parse back as 0 */
    }
    hal_can_frame_t g;
    memset(&g, 0, sizeof g);
    if (candump_parse_line(buf, n - 1u, &g) != CANDUMP_FRAME || !same_frame(&f, &g)) {
        fuzz_fail("candump_format_line: '%.*s' does not parse back", (int)(n - 1u), buf);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    hal_can_frame_t f;
    (void)parse_checked((const char *)data, size, &f);
    check_reader(data, size);
    check_format(data, size);
    return 0;
}
