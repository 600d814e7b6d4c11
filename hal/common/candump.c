/*
 * candump.c - the candump log line, parsed and written (contracts in candump.h).
 *
 * Parsed by hand, not with sscanf: every malformed form must be caught, the timestamp
 * converted without floating point, and nothing may depend on the locale or on stdio
 * (the Cortex-M4F build has none).
 */
#include "candump.h"

#define US_PER_S UINT64_C(1000000)
#define STD_ID_MAX UINT32_C(0x7FF)
#define EXT_ID_MAX UINT32_C(0x1FFFFFFF)
#define FRAC_DIGITS_MAX 9u

static int is_blank(char c)
{
    return c == ' ' || c == '\t' || c == '\r';
}

/* printable ASCII other than space: what an interface name may hold */
static int is_graph_ascii(char c)
{
    return c > ' ' && c <= '~';
}

static int is_digit(char c)
{
    return c >= '0' && c <= '9';
}

/* value of hex digit c, or -1 */
static int hex_value(char c)
{
    if (c >= '0' && c <= '9') {
        return c - '0';
    }
    if (c >= 'a' && c <= 'f') {
        return c - 'a' + 10;
    }
    if (c >= 'A' && c <= 'F') {
        return c - 'A' + 10;
    }
    return -1;
}

static size_t skip_blanks(const char *s, size_t i, size_t n)
{
    while (i < n && is_blank(s[i])) {
        i++;
    }
    return i;
}

/*
 * Parse "(seconds.fraction)" at s[*i..n) into *t_us; advance *i past ")". Returns 0, or
 * -1 if malformed or out of the uint64_t microsecond range.
 */
static int parse_timestamp(const char *s, size_t *i, size_t n, uint64_t *t_us)
{
    size_t k = *i;
    uint64_t sec = 0u;
    uint64_t frac_us = 0u;
    unsigned n_sec = 0u;
    unsigned n_frac = 0u;

    if (k >= n || s[k] != '(') {
        return -1;
    }
    k++;
    while (k < n && is_digit(s[k])) {
        const uint64_t d = (uint64_t)(s[k] - '0');
        if (sec > (UINT64_MAX - d) / 10u) {
            return -1;
        }
        sec = sec * 10u + d;
        n_sec++;
        k++;
    }
    if (n_sec == 0u || k >= n || s[k] != '.') {
        return -1;
    }
    k++;
    while (k < n && is_digit(s[k])) {
        if (n_frac >= FRAC_DIGITS_MAX) {
            return -1;
        }
        /* the first six digits are microseconds; later ones are below 1 us: truncated */
        if (n_frac < 6u) {
            frac_us = frac_us * 10u + (uint64_t)(s[k] - '0');
        }
        n_frac++;
        k++;
    }
    if (n_frac == 0u || k >= n || s[k] != ')') {
        return -1;
    }
    k++;
    for (unsigned j = n_frac; j < 6u; j++) {
        frac_us *= 10u;
    }
    if (sec > (UINT64_MAX - frac_us) / US_PER_S) {
        return -1;
    }
    *t_us = sec * US_PER_S + frac_us;
    *i = k;
    return 0;
}

/*
 * Parse "ID#DATA" occupying exactly s[i..n) into *f (id, extended, dlc, data). Returns 0,
 * or -1 if malformed, remote, CAN FD, or an error frame.
 */
static int parse_frame(const char *s, size_t i, size_t n, hal_can_frame_t *f)
{
    uint32_t id = 0u;
    size_t n_id = 0u;

    while (i < n && s[i] != '#') {
        const int v = hex_value(s[i]);
        if (v < 0 || n_id >= 8u) {
            return -1;
        }
        id = (id << 4) | (uint32_t)v;
        n_id++;
        i++;
    }
    if (i >= n) {
        return -1; /* no '#' */
    }
    if (n_id == 3u) {
        if (id > STD_ID_MAX) {
            return -1;
        }
        f->extended = 0u;
    } else if (n_id == 8u) {
        /* also rejects error frames and anything else with flag bits above bit 28 */
        if (id > EXT_ID_MAX) {
            return -1;
        }
        f->extended = 1u;
    } else {
        return -1;
    }
    f->id = id;
    i++; /* '#'; a following '#' (CAN FD) or 'R' (remote) fails the hex test below */

    const size_t n_hex = n - i;
    if (n_hex % 2u != 0u || n_hex > 16u) {
        return -1;
    }
    for (size_t b = 0u; b < n_hex / 2u; b++) {
        const int hi = hex_value(s[i + 2u * b]);
        const int lo = hex_value(s[i + 2u * b + 1u]);
        if (hi < 0 || lo < 0) {
            return -1;
        }
        f->data[b] = (uint8_t)((hi << 4) | lo);
    }
    f->dlc = (uint8_t)(n_hex / 2u);
    return 0;
}

candump_line_t candump_parse_line(const char *s, size_t n, hal_can_frame_t *f)
{
    hal_can_frame_t g = {0};
    size_t i = skip_blanks(s, 0u, n);

    if (i == n) {
        return CANDUMP_BLANK;
    }
    if (parse_timestamp(s, &i, n, &g.t_us) != 0) {
        return CANDUMP_MALFORMED;
    }

    /* interface */
    size_t start = skip_blanks(s, i, n);
    if (start == i) {
        return CANDUMP_MALFORMED; /* no blank after ")" */
    }
    i = start;
    while (i < n && is_graph_ascii(s[i])) {
        i++;
    }
    if (i == start || i - start > CANDUMP_IFACE_MAX || i == n || !is_blank(s[i])) {
        return CANDUMP_MALFORMED;
    }

    /* frame, then an optional direction token ("R" or "T", as python-can and newer
     * candump write it), then nothing but blanks */
    start = skip_blanks(s, i, n);
    i = start;
    while (i < n && !is_blank(s[i])) {
        i++;
    }
    if (i == start) {
        return CANDUMP_MALFORMED;
    }
    size_t rest = skip_blanks(s, i, n);
    if (rest < n && rest > i && (s[rest] == 'R' || s[rest] == 'T')) {
        rest = skip_blanks(s, rest + 1u, n);
    }
    if (rest != n) {
        return CANDUMP_MALFORMED;
    }
    if (parse_frame(s, start, i, &g) != 0) {
        return CANDUMP_MALFORMED;
    }
    *f = g;
    return CANDUMP_FRAME;
}

/* write v as `digits` uppercase hex digits at p; returns p + digits */
static char *put_hex(char *p, uint32_t v, unsigned digits)
{
    static const char hex[] = "0123456789ABCDEF";
    for (unsigned d = digits; d > 0u; d--) {
        p[d - 1u] = hex[v & 0xFu];
        v >>= 4;
    }
    return p + digits;
}

/* write v in decimal, zero-padded to at least min_digits, at p; returns the end */
static char *put_dec(char *p, uint64_t v, unsigned min_digits)
{
    char rev[20]; /* UINT64_MAX has 20 digits */
    unsigned n = 0u;
    do {
        rev[n++] = (char)('0' + (char)(v % 10u));
        v /= 10u;
    } while (v != 0u);
    while (n < min_digits && n < sizeof rev) {
        rev[n++] = '0';
    }
    while (n > 0u) {
        *p++ = rev[--n];
    }
    return p;
}

size_t candump_format_line(char *buf, size_t cap, uint64_t t_us, const char *iface,
                           const hal_can_frame_t *f)
{
    char line[CANDUMP_FORMAT_MAX];
    size_t n_iface = 0u;

    if (buf == NULL || iface == NULL || f == NULL || f->dlc > 8u || f->extended > 1u ||
        f->id > (f->extended != 0u ? EXT_ID_MAX : STD_ID_MAX)) {
        return 0u;
    }
    while (n_iface <= CANDUMP_IFACE_MAX && iface[n_iface] != '\0') {
        if (!is_graph_ascii(iface[n_iface])) {
            return 0u;
        }
        n_iface++;
    }
    if (n_iface == 0u || n_iface > CANDUMP_IFACE_MAX) {
        return 0u;
    }
    char *p = line;
    *p++ = '(';
    p = put_dec(p, t_us / US_PER_S, 10u);
    *p++ = '.';
    p = put_dec(p, t_us % US_PER_S, 6u);
    *p++ = ')';
    *p++ = ' ';
    for (size_t k = 0u; k < n_iface; k++) {
        *p++ = iface[k];
    }
    *p++ = ' ';
    p = put_hex(p, f->id, f->extended != 0u ? 8u : 3u);
    *p++ = '#';
    for (unsigned b = 0u; b < f->dlc; b++) {
        p = put_hex(p, f->data[b], 2u);
    }
    *p++ = '\n';
    const size_t len = (size_t)(p - line);
    if (len > cap) {
        return 0u;
    }
    for (size_t k = 0u; k < len; k++) {
        buf[k] = line[k];
    }
    return len;
}

/*
 * Read lines from a byte source until one holds a frame: each line's first cap
 * characters are kept in line[0..cap) (the rest of a longer line is read and dropped),
 * then parsed by candump_parse_line. A malformed or overlong line adds one to *malformed
 * (saturating) and is skipped; a blank line is skipped; a last line without a newline is
 * parsed like any other. Returns 0 with *f filled, HAL_ENODATA at the end of the source
 * (the caller should not read again), or HAL_EIO on a read error.
 */
static int candump_read(candump_next_byte_t next, void *ctx, char *line, size_t cap,
                        hal_can_frame_t *f, uint32_t *malformed)
{
    for (;;) {
        size_t n = 0u;
        int overlong = 0;
        int c;
        while ((c = next(ctx)) >= 0 && c != (int)'\n') {
            if (n < cap) {
                line[n] = (char)c;
                n++;
            } else {
                overlong = 1;
            }
        }
        if (c == CANDUMP_SRC_ERROR) {
            return HAL_EIO;
        }
        if (c == CANDUMP_SRC_END && n == 0u && !overlong) {
            return HAL_ENODATA;
        }
        /* else a whole line, or a last line without newline (the next call ends) */
        candump_line_t kind = CANDUMP_MALFORMED;
        if (!overlong) {
            kind = candump_parse_line(line, n, f);
        }
        if (kind == CANDUMP_FRAME) {
            return 0;
        }
        if (kind == CANDUMP_MALFORMED && *malformed != UINT32_MAX) {
            (*malformed)++;
        }
    }
}

int candump_replay(candump_rx_t *rx, candump_next_byte_t next, void *ctx, char *line,
                   size_t cap, hal_can_frame_t *f)
{
    if (rx->eof != 0u) {
        return HAL_ENODATA;
    }
    const int rc = candump_read(next, ctx, line, cap, f, &rx->malformed);
    if (rc == HAL_ENODATA) {
        rx->eof = 1u;
    } else if (rc == 0) {
        rx->t_us = f->t_us;
        rx->frames = rx->frames == UINT32_MAX ? rx->frames : rx->frames + 1u;
    } else {
        /* HAL_EIO: returned as it is */
    }
    return rc;
}
