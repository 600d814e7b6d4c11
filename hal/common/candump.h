/*
 * candump.h - the candump log line (can-utils `candump -l`), parsed and written without
 * stdio, locale, floating point or allocation, so that every HAL that replays or records
 * a log uses the same code: the Linux host (hal/linux/hal_linux.c) and the Cortex-M4F
 * under QEMU with semihosting (hal/cortex_m4f/hal_semihost.c). Frames a log line cannot
 * carry on a classic CAN bus are malformed here, never silently changed.
 *
 * Line format, one frame per line:
 *     (1436509052.249713) vcan0 123#DEADBEEF
 * - timestamp: "(" seconds "." 1..9 fraction digits ")", decimal; converted to integer
 *   microseconds exactly (digits past the sixth are truncated, never rounded); it must fit
 *   a uint64_t in microseconds;
 * - interface: 1..CANDUMP_IFACE_MAX printable non-blank ASCII characters;
 * - frame: 3 hex digits (standard ID <= 0x7FF) or 8 hex digits (extended ID < 2^29), "#",
 *   then 0..8 data bytes as pairs of hex digits; upper or lower case;
 * - an optional direction token "R" or "T" after the frame (python-can and newer candump
 *   write it).
 * Fields are separated by runs of spaces or tabs; blanks (space, tab, CR) before the first
 * and after the last field are ignored, so CRLF logs parse. A line of only blanks is
 * CANDUMP_BLANK. Everything else is CANDUMP_MALFORMED: garbage, unbalanced parentheses, a
 * missing field or an extra one, bad hex, an odd number of data digits, more than 8 data
 * bytes, an ID out of range for its digit count or with another digit count, remote
 * frames ("123#R"), CAN FD frames ("123##..."), error frames (the CAN_ERR_FLAG makes an
 * 8-digit ID >= 0x20000000).
 */
#ifndef NAVECU_CANDUMP_H
#define NAVECU_CANDUMP_H

#include <stddef.h>
#include <stdint.h>

#include "hal.h"

#define CANDUMP_IFACE_MAX 15u /* longest interface name (Linux IFNAMSIZ - 1) */
/* longest line candump_format_line writes, newline included, no NUL: "(" 20 digits "."
 * 6 digits ") " iface " " 8 digits "#" 16 digits "\n" */
#define CANDUMP_FORMAT_MAX (1u + 20u + 1u + 6u + 2u + CANDUMP_IFACE_MAX + 1u + 8u + 1u + 16u + 1u)

typedef enum { CANDUMP_FRAME, CANDUMP_BLANK, CANDUMP_MALFORMED } candump_line_t;

/*
 * Classify one line s[0..n) (its newline removed; need not be NUL-terminated; s may be
 * NULL only with n == 0). On CANDUMP_FRAME *f is filled completely (t_us the line's
 * timestamp, unused data bytes 0); otherwise *f is unchanged.
 */
candump_line_t candump_parse_line(const char *s, size_t n, hal_can_frame_t *f);

/*
 * Write f as "(SSSSSSSSSS.UUUUUU) IFACE ID#DATA\n" stamped t_us into buf[0..cap): ID as
 * 3 (standard) or 8 (extended) uppercase hex digits, data as uppercase hex pairs, seconds
 * zero-padded to at least 10 digits. iface must be 1..CANDUMP_IFACE_MAX printable
 * non-blank ASCII characters, NUL-terminated. Returns the number of characters written
 * (no NUL is added), or 0 when f is not a classic frame (dlc > 8, extended not 0 or 1, ID
 * too wide), iface is not valid, or cap is too small (CANDUMP_FORMAT_MAX always fits).
 * What it writes parses back with candump_parse_line to the same frame and time.
 */
size_t candump_format_line(char *buf, size_t cap, uint64_t t_us, const char *iface,
                           const hal_can_frame_t *f);

/* A byte source for candump_replay: the next byte 0..255, CANDUMP_SRC_END at its end, or
 * CANDUMP_SRC_ERROR on a read error. */
#define CANDUMP_SRC_END (-1)
#define CANDUMP_SRC_ERROR (-2)
typedef int (*candump_next_byte_t)(void *ctx);

/* A log replayed as CAN receive: its clock (the last frame's timestamp, 0 before any),
 * the malformed lines skipped and the frames returned (both saturating), and its end. */
typedef struct {
    uint64_t t_us;
    uint32_t malformed;
    uint32_t frames;
    uint8_t eof;
} candump_rx_t;

/*
 * The next frame of a replay: HAL_ENODATA once the source has ended (it is not read
 * again), else the result of reading lines until one holds a frame (candump.c); a frame sets the replay's clock and is counted.
 */
int candump_replay(candump_rx_t *rx, candump_next_byte_t next, void *ctx, char *line,
                   size_t cap, hal_can_frame_t *f);

#endif /* NAVECU_CANDUMP_H */
