/* Host unit tests of the portable core: shared vectors, fuzzing, watchdog, clamps, slew.
 *
 *   test_core VECTORS_FILE [FUZZ_ROUNDS]
 *
 * Exits 0 when every check passes. Built by `make -C firmware test` (and `test-asan` with
 * -fsanitize=address,undefined). Test code may use the C library freely; the core may not. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "chair_core.h"
#include "proto_parser.h"
#include "proto_wire.h"

static int g_checks = 0, g_failures = 0;

#define CHECK(cond) check_((cond) ? 1 : 0, #cond, __FILE__, __LINE__)
#define CHECK_EQ(a, b) check_eq_((long long)(a), (long long)(b), #a, #b, __FILE__, __LINE__)

static int check_(int ok, const char *what, const char *file, int line)
{
    g_checks++;
    if (!ok) {
        g_failures++;
        fprintf(stderr, "%s:%d: check failed: %s\n", file, line, what);
    }
    return ok;
}

static int check_eq_(long long a, long long b, const char *ea, const char *eb, const char *file, int line)
{
    g_checks++;
    if (a != b) {
        g_failures++;
        fprintf(stderr, "%s:%d: check failed: %s == %s (%lld != %lld)\n", file, line, ea, eb, a, b);
        return 0;
    }
    return 1;
}

/* ---- deterministic PRNG (xorshift32) -------------------------------------------------------- */
static uint32_t g_rng = 0x12345678u;
static uint32_t rnd(void)
{
    g_rng ^= g_rng << 13;
    g_rng ^= g_rng >> 17;
    g_rng ^= g_rng << 5;
    return g_rng;
}
static uint32_t rnd_below(uint32_t n) { return n ? rnd() % n : 0; }

/* ---- a chair with a fake clock and captured I/O --------------------------------------------- */
typedef struct {
    uint8_t tx[8192];
    size_t tx_n;
    int events[8];
    int last_rx_error;
    int frame_events;
    int inconsistent; /* fuzz: applied frames whose content does not match their sequence number */
    int check_consistency;
} harness_t;

static size_t cap_write(void *ctx, const uint8_t *d, size_t n)
{
    harness_t *h = (harness_t *)ctx;
    if (h->tx_n + n > sizeof h->tx) return 0;
    memcpy(h->tx + h->tx_n, d, n);
    h->tx_n += n;
    return n;
}

static uint8_t pattern_motor(uint16_t seq, unsigned i) { return (uint8_t)((seq * 7u + i * 13u) & 0xFFu); }
static uint8_t pattern_fan(uint16_t seq, unsigned j) { return (uint8_t)((seq * 3u + j) & 0xFFu); }
static int16_t pattern_temp(uint16_t seq) { return (int16_t)(2000 + (seq % 1900u)); }

static void cap_event(void *ctx, chair_event_t ev, int status, const chair_t *c)
{
    harness_t *h = (harness_t *)ctx;
    if ((int)ev >= 0 && (int)ev < 8) h->events[ev]++;
    if (ev == CHAIR_EV_RX_ERROR) h->last_rx_error = status;
    if (ev == CHAIR_EV_FRAME) {
        h->frame_events++;
        if (h->check_consistency) {
            unsigned i;
            int bad = 0;
            for (i = 0; i < AH_N_MOTORS; i++) bad |= c->out.motors[i] != pattern_motor(c->last_seq, i);
            for (i = 0; i < AH_N_FANS; i++) bad |= c->out.fans[i] != pattern_fan(c->last_seq, i);
            bad |= c->out.temp_target_cc != chair_clamp_temp(pattern_temp(c->last_seq));
            bad |= c->last_tick != (uint32_t)c->last_seq * 2u;
            h->inconsistent += bad;
        }
    }
}

static void setup(chair_t *c, harness_t *h, uint32_t now)
{
    chair_io_t io;
    memset(h, 0, sizeof *h);
    io.write = cap_write;
    io.event = cap_event;
    io.ctx = h;
    chair_init(c, &io, now);
}

static size_t wire_of(const ah_msg_t *m, uint8_t *out, size_t cap)
{
    size_t n = ah_encode_msg(m, out, cap);
    CHECK(n > 0);
    return n;
}

static void make_frame(ah_msg_t *m, uint32_t tick, uint16_t seq, uint8_t motor, int16_t temp, uint8_t fan)
{
    memset(m, 0, sizeof *m);
    m->type = AH_MSG_FRAME;
    m->u.frame.tick = tick;
    m->u.frame.seq = seq;
    memset(m->u.frame.motors, motor, AH_N_MOTORS);
    memset(m->u.frame.fans, fan, AH_N_FANS);
    m->u.frame.temp_cc = temp;
}

static void send_frame(chair_t *c, uint32_t now, uint32_t tick, uint16_t seq, uint8_t motor, int16_t temp, uint8_t fan)
{
    ah_msg_t m;
    uint8_t w[AH_MAX_ENCODED + 1];
    make_frame(&m, tick, seq, motor, temp, fan);
    chair_update(c, w, wire_of(&m, w, sizeof w), now);
}

static void send_empty(chair_t *c, uint32_t now, uint8_t type)
{
    ah_msg_t m;
    uint8_t w[16];
    memset(&m, 0, sizeof m);
    m.type = type;
    chair_update(c, w, wire_of(&m, w, sizeof w), now);
}

/* Decode every reply the chair sent; returns how many, the last one in *last. */
static int replies(harness_t *h, ah_msg_t *last)
{
    ah_parser_t p;
    ah_msg_t m;
    size_t i;
    int count = 0;
    ah_parser_init(&p, 0, 0);
    for (i = 0; i < h->tx_n; i++) {
        ah_status_t st = ah_parser_feed(&p, h->tx[i], &m);
        if (st == AH_PENDING) continue;
        CHECK_EQ(st, AH_OK);
        if (st == AH_OK) {
            *last = m;
            count++;
        }
    }
    h->tx_n = 0;
    return count;
}

/* ---- vectors ---------------------------------------------------------------------------------- */
static int hex_decode(const char *s, uint8_t *out, size_t cap)
{
    size_t n = 0;
    if (strcmp(s, "-") == 0) return 0;
    while (s[0] && s[1]) {
        unsigned v;
        if (n >= cap || sscanf(s, "%2x", &v) != 1) return -1;
        out[n++] = (uint8_t)v;
        s += 2;
    }
    return s[0] ? -1 : (int)n;
}

static const char *status_names[] = {"ok", "crc_error", "length_error", "overflow", "version_error", "type_error"};
static const ah_status_t status_values[] = {AH_OK, AH_ERR_CRC, AH_ERR_LENGTH, AH_ERR_OVERFLOW, AH_ERR_VERSION, AH_ERR_TYPE};

static int parse_status(const char *s)
{
    size_t i;
    for (i = 0; i < sizeof status_names / sizeof status_names[0]; i++)
        if (strcmp(s, status_names[i]) == 0) return (int)status_values[i];
    return 99;
}

typedef struct {
    int statuses[16];
    int n;
    ah_msg_t ok;
    int n_ok;
} collect_t;

static void collect(void *ctx, ah_status_t st, const ah_msg_t *msg)
{
    collect_t *c = (collect_t *)ctx;
    if (c->n < 16) c->statuses[c->n] = (int)st;
    c->n++;
    if (st == AH_OK) {
        c->ok = *msg;
        c->n_ok++;
    }
}

static int read_ints(const char *s, long *v, int max)
{
    int n = 0;
    char *end;
    while (n < max) {
        long x = strtol(s, &end, 10);
        if (end == s) break;
        v[n++] = x;
        s = end;
    }
    return n;
}

/* Compare one "<field> <values>" line of a vector with the decoded message. */
static void check_field(const char *vec, const ah_msg_t *m, const char *key, const char *rest)
{
    long v[200];
    int n = read_ints(rest, v, 200), ok = 1;
    long got = 0;
    int i;
    if (m->type == AH_MSG_FRAME) {
        const ah_frame_t *f = &m->u.frame;
        if (strcmp(key, "motors") == 0) {
            ok = n == (int)AH_N_MOTORS;
            for (i = 0; ok && i < n; i++) ok = f->motors[i] == v[i];
        } else if (strcmp(key, "fans") == 0) {
            ok = n == (int)AH_N_FANS;
            for (i = 0; ok && i < n; i++) ok = f->fans[i] == v[i];
        } else {
            if (strcmp(key, "tick") == 0) got = (long)f->tick;
            else if (strcmp(key, "seq") == 0) got = f->seq;
            else if (strcmp(key, "temp_cc") == 0) got = f->temp_cc;
            else ok = 0;
            ok = ok && n == 1 && got == v[0];
        }
    } else if (m->type == AH_MSG_HELLO) {
        const ah_hello_t *h = &m->u.hello;
        if (strcmp(key, "firmware_version") == 0) {
            ok = n == 3 && h->fw_major == v[0] && h->fw_minor == v[1] && h->fw_patch == v[2];
        } else if (strcmp(key, "name") == 0) {
            char name[AH_NAME_LEN + 1];
            memcpy(name, h->name, AH_NAME_LEN);
            name[AH_NAME_LEN] = '\0';
            ok = strcmp(name, rest) == 0;
        } else {
            if (strcmp(key, "protocol_version") == 0) got = h->protocol_version;
            else if (strcmp(key, "n_actuators") == 0) got = h->n_actuators;
            else if (strcmp(key, "fan_rows") == 0) got = h->fan_rows;
            else if (strcmp(key, "fan_cols") == 0) got = h->fan_cols;
            else if (strcmp(key, "temp_min_cc") == 0) got = h->temp_min_cc;
            else if (strcmp(key, "temp_max_cc") == 0) got = h->temp_max_cc;
            else if (strcmp(key, "temp_neutral_cc") == 0) got = h->temp_neutral_cc;
            else if (strcmp(key, "temp_rate_cc_per_s") == 0) got = h->temp_rate_cc_per_s;
            else if (strcmp(key, "watchdog_ms") == 0) got = h->watchdog_ms;
            else if (strcmp(key, "tick_ms") == 0) got = h->tick_ms;
            else if (strcmp(key, "max_packet") == 0) got = h->max_packet;
            else ok = 0;
            ok = ok && n == 1 && got == v[0];
        }
    } else if (m->type == AH_MSG_STATUS) {
        const ah_status_msg_t *s = &m->u.status;
        if (strcmp(key, "uptime_ms") == 0) got = (long)s->uptime_ms;
        else if (strcmp(key, "frames_ok") == 0) got = (long)s->frames_ok;
        else if (strcmp(key, "packets_ok") == 0) got = (long)s->packets_ok;
        else if (strcmp(key, "crc_errors") == 0) got = (long)s->crc_errors;
        else if (strcmp(key, "length_errors") == 0) got = (long)s->length_errors;
        else if (strcmp(key, "overflows") == 0) got = (long)s->overflows;
        else if (strcmp(key, "version_errors") == 0) got = (long)s->version_errors;
        else if (strcmp(key, "type_errors") == 0) got = (long)s->type_errors;
        else if (strcmp(key, "stale_frames") == 0) got = (long)s->stale_frames;
        else if (strcmp(key, "seq_gaps") == 0) got = (long)s->seq_gaps;
        else if (strcmp(key, "late_frames") == 0) got = (long)s->late_frames;
        else if (strcmp(key, "watchdog_trips") == 0) got = (long)s->watchdog_trips;
        else if (strcmp(key, "tx_dropped") == 0) got = (long)s->tx_dropped;
        else if (strcmp(key, "last_tick") == 0) got = (long)s->last_tick;
        else if (strcmp(key, "last_seq") == 0) got = s->last_seq;
        else if (strcmp(key, "flags") == 0) got = s->flags;
        else if (strcmp(key, "safe_reason") == 0) got = s->safe_reason;
        else if (strcmp(key, "temp_target_cc") == 0) got = s->temp_target_cc;
        else if (strcmp(key, "temp_setpoint_cc") == 0) got = s->temp_setpoint_cc;
        else ok = 0;
        ok = ok && n == 1 && got == v[0];
    } else {
        ok = 0; /* messages without payload have no fields */
    }
    if (!check_(ok, key, vec, 0)) fprintf(stderr, "  vector %s: field %s does not match\n", vec, key);
}

static void run_vector(const char *name, const uint8_t *wire, size_t n, const int *expect, int n_expect, int canonical,
                       int type, char fields[][2048], int n_fields)
{
    ah_parser_t p;
    collect_t col;
    int i;
    uint8_t *exact = (uint8_t *)malloc(n ? n : 1); /* exact-size heap copy: ASan sees any over-read */
    memset(&col, 0, sizeof col);
    memcpy(exact, wire, n);
    ah_parser_init(&p, collect, &col);
    ah_parser_update(&p, exact, n);
    free(exact);
    if (!CHECK_EQ(col.n, n_expect)) fprintf(stderr, "  vector %s\n", name);
    for (i = 0; i < n_expect && i < col.n; i++)
        if (!CHECK_EQ(col.statuses[i], expect[i])) fprintf(stderr, "  vector %s result %d\n", name, i);
    if (type >= 0) {
        if (!CHECK_EQ(col.n_ok, 1)) return;
        CHECK_EQ(col.ok.type, type);
        for (i = 0; i < n_fields; i++) {
            char key[64];
            const char *sp = strchr(fields[i], ' ');
            size_t k = sp ? (size_t)(sp - fields[i]) : strlen(fields[i]);
            if (k >= sizeof key) k = sizeof key - 1;
            memcpy(key, fields[i], k);
            key[k] = '\0';
            check_field(name, &col.ok, key, sp ? sp + 1 : "");
        }
    }
    if (canonical && col.n_ok == 1) {
        uint8_t out[AH_MAX_ENCODED + 1];
        size_t m = ah_encode_msg(&col.ok, out, sizeof out);
        if (!(CHECK_EQ(m, n) && CHECK(memcmp(out, wire, n) == 0))) fprintf(stderr, "  vector %s: encoding differs\n", name);
    }
}

static void test_vectors(const char *path)
{
    static char line[8192];
    static char fields[64][2048];
    static uint8_t wire[1024];
    FILE *f = fopen(path, "r");
    char name[128] = "";
    int in_vec = 0, n_fields = 0, canonical = 0, type = -1, expect[16], n_expect = 0, n_vectors = 0, n_misc = 0;
    long wire_n = 0;
    if (!CHECK(f != NULL)) {
        perror(path);
        return;
    }
    while (fgets(line, sizeof line, f)) {
        char *nl = strpbrk(line, "\r\n");
        char a[1024], b[1024];
        if (nl) *nl = '\0';
        if (line[0] == '#' || line[0] == '\0') continue;
        if (!in_vec && strncmp(line, "crc ", 4) == 0 && sscanf(line + 4, "%1023s %1023s", a, b) == 2) {
            uint8_t data[512];
            int n = hex_decode(a, data, sizeof data);
            CHECK(n >= 0);
            CHECK_EQ(ah_crc16(data, (size_t)n), strtol(b, NULL, 16));
            n_misc++;
        } else if (!in_vec && strncmp(line, "cobs ", 5) == 0 && sscanf(line + 5, "%1023s %1023s", a, b) == 2) {
            uint8_t dec[512], enc[512], out[600];
            int nd = hex_decode(a, dec, sizeof dec), ne = hex_decode(b, enc, sizeof enc);
            size_t m, back = 0;
            CHECK(nd >= 0 && ne > 0);
            m = ah_cobs_encode(dec, (size_t)nd, out, sizeof out);
            CHECK_EQ(m, ne);
            CHECK(memcmp(out, enc, (size_t)ne) == 0);
            CHECK_EQ(ah_cobs_decode_inplace(enc, (size_t)ne, &back), AH_OK);
            CHECK_EQ(back, nd);
            CHECK(memcmp(enc, dec, (size_t)nd) == 0);
            n_misc++;
        } else if (!in_vec && strncmp(line, "vector ", 7) == 0 && sscanf(line + 7, "%127s", name) == 1) {
            in_vec = 1;
            n_fields = 0;
            canonical = 0;
            type = -1;
            n_expect = 0;
            wire_n = 0;
        } else if (in_vec && strcmp(line, "end") == 0) {
            run_vector(name, wire, (size_t)wire_n, expect, n_expect, canonical, type, fields, n_fields);
            in_vec = 0;
            n_vectors++;
        } else if (in_vec && strncmp(line, "wire ", 5) == 0) {
            wire_n = hex_decode(line + 5, wire, sizeof wire);
            CHECK(wire_n >= 0);
        } else if (in_vec && strncmp(line, "results ", 8) == 0) {
            char *tok = strtok(line + 7, " ");
            for (; tok != NULL && n_expect < 16; tok = strtok(NULL, " ")) {
                expect[n_expect] = parse_status(tok);
                CHECK(expect[n_expect] != 99);
                n_expect++;
            }
        } else if (in_vec && strcmp(line, "canonical") == 0) {
            canonical = 1;
        } else if (in_vec && strncmp(line, "type ", 5) == 0 && sscanf(line + 5, "%1023s", a) == 1) {
            type = (int)strtol(a, NULL, 16);
        } else if (in_vec && n_fields < 64 && strlen(line) < sizeof fields[0]) {
            strcpy(fields[n_fields++], line);
        } else {
            CHECK(!"unrecognised line in the vectors file");
            fprintf(stderr, "  line: %.80s\n", line);
        }
    }
    fclose(f);
    CHECK(!in_vec);
    CHECK(n_vectors >= 20);
    CHECK(n_misc >= 5);
    printf("vectors: %d frame vectors, %d crc/cobs vectors\n", n_vectors, n_misc);
}

/* ---- behaviour ------------------------------------------------------------------------------ */
static void test_boot_and_hello(void)
{
    chair_t c;
    harness_t h;
    ah_msg_t r;
    setup(&c, &h, 1000);
    CHECK(c.flags & AH_FLAG_SAFE);
    CHECK_EQ(c.safe_reason, AH_SAFE_BOOT);
    CHECK_EQ(c.out.temp_setpoint_cc, AH_TEMP_NEUTRAL_CC);
    send_empty(&c, 1001, AH_MSG_HELLO_REQ);
    CHECK_EQ(replies(&h, &r), 1);
    CHECK_EQ(r.type, AH_MSG_HELLO);
    CHECK_EQ(r.u.hello.protocol_version, AH_PROTOCOL_VERSION);
    CHECK_EQ(r.u.hello.n_actuators, 9);
    CHECK_EQ(r.u.hello.fan_rows, 9);
    CHECK_EQ(r.u.hello.fan_cols, 17);
    CHECK_EQ(r.u.hello.temp_max_cc, AH_TEMP_MAX_CC);
    CHECK_EQ(r.u.hello.temp_min_cc, AH_TEMP_MIN_CC);
    CHECK_EQ(r.u.hello.temp_neutral_cc, AH_TEMP_NEUTRAL_CC);
    CHECK_EQ(r.u.hello.watchdog_ms, AH_WATCHDOG_MS);
    send_empty(&c, 1500, AH_MSG_STATUS_REQ);
    CHECK_EQ(replies(&h, &r), 1);
    CHECK_EQ(r.type, AH_MSG_STATUS);
    CHECK_EQ(r.u.status.uptime_ms, 500);
    CHECK_EQ(r.u.status.packets_ok, 2);
    CHECK_EQ(r.u.status.flags & AH_FLAG_HAS_TICK, 0);
}

static void test_frame_applied_whole(void)
{
    chair_t c;
    harness_t h;
    ah_msg_t m;
    uint8_t w[AH_MAX_ENCODED + 1];
    size_t n, i;
    setup(&c, &h, 0);
    make_frame(&m, 77, 1, 200, 3600, 50);
    m.u.frame.motors[8] = 9;
    m.u.frame.fans[152] = 251;
    n = wire_of(&m, w, sizeof w);
    /* byte by byte: nothing changes until the delimiter */
    for (i = 0; i + 1 < n; i++) {
        chair_update(&c, w + i, 1, 1);
        CHECK_EQ(c.out.motors[0], 0);
        CHECK_EQ(h.frame_events, 0);
    }
    chair_update(&c, w + n - 1, 1, 2);
    CHECK_EQ(h.frame_events, 1);
    CHECK_EQ(c.out.motors[0], 200);
    CHECK_EQ(c.out.motors[8], 9);
    CHECK_EQ(c.out.fans[0], 50);
    CHECK_EQ(c.out.fans[152], 251);
    CHECK_EQ(c.out.temp_target_cc, 3600);
    CHECK_EQ(c.last_tick, 77);
    CHECK(!(c.flags & AH_FLAG_SAFE));
    /* the same frame with a flipped bit is dropped whole */
    make_frame(&m, 78, 2, 1, 3000, 2);
    n = wire_of(&m, w, sizeof w);
    w[40] ^= 0x04;
    chair_update(&c, w, n, 50);
    CHECK_EQ(h.frame_events, 1);
    CHECK_EQ(c.out.motors[0], 200);
    CHECK_EQ(c.out.fans[0], 50);
    CHECK_EQ(c.last_tick, 77);
    CHECK_EQ(c.parser.cnt.crc_errors + c.parser.cnt.length_errors, 1);
    /* a truncated frame followed by a good one: the good one applies, the stub is counted */
    make_frame(&m, 79, 3, 5, 3000, 6);
    n = wire_of(&m, w, sizeof w);
    chair_update(&c, w, 90, 60);
    w[0] = 0;
    chair_update(&c, w, 1, 60);
    make_frame(&m, 80, 4, 7, 3100, 8);
    n = wire_of(&m, w, sizeof w);
    chair_update(&c, w, n, 61);
    CHECK_EQ(c.last_tick, 80);
    CHECK_EQ(c.out.motors[3], 7);
    CHECK_EQ(c.parser.cnt.length_errors >= 1, 1);
}

static void test_watchdog(void)
{
    chair_t c;
    harness_t h;
    ah_msg_t r;
    uint32_t t;
    setup(&c, &h, 5000);
    send_frame(&c, 5000, 1, 1, 128, 3800, 99);
    h.tx_n = 0;
    for (t = 5001; t < 5000 + AH_WATCHDOG_MS; t++) {
        chair_update(&c, NULL, 0, t);
        if (c.flags & AH_FLAG_SAFE) break;
    }
    CHECK_EQ(t, 5000 + AH_WATCHDOG_MS); /* still running 1 ms before the deadline */
    CHECK_EQ(c.out.motors[4], 128);
    chair_update(&c, NULL, 0, 5000 + AH_WATCHDOG_MS);
    CHECK(c.flags & AH_FLAG_SAFE);
    CHECK_EQ(c.safe_reason, AH_SAFE_WATCHDOG);
    CHECK_EQ(c.out.motors[4], 0);
    CHECK_EQ(c.out.fans[100], 0);
    CHECK_EQ(c.out.temp_target_cc, AH_TEMP_NEUTRAL_CC);
    CHECK_EQ(c.cnt.watchdog_trips, 1);
    CHECK_EQ(h.events[CHAIR_EV_SAFE], 1);
    CHECK_EQ(replies(&h, &r), 1); /* the chair reports the trip */
    CHECK_EQ(r.type, AH_MSG_STATUS);
    CHECK(r.u.status.flags & AH_FLAG_SAFE);
    CHECK_EQ(r.u.status.safe_reason, AH_SAFE_WATCHDOG);
    /* staying safe does not re-trip; a new frame resumes */
    chair_update(&c, NULL, 0, 9000);
    CHECK_EQ(c.cnt.watchdog_trips, 1);
    send_frame(&c, 9001, 2, 2, 10, 3300, 0);
    CHECK(!(c.flags & AH_FLAG_SAFE));
    CHECK_EQ(c.out.motors[0], 10);
    CHECK_EQ(c.cnt.late_frames, 0); /* a stream restarting after the safe state is not late */
}

static void test_watchdog_across_millis_wrap(void)
{
    chair_t c;
    harness_t h;
    uint32_t t0 = 0xFFFFFF00u, k;
    setup(&c, &h, t0);
    for (k = 0; k < 20; k++) {
        uint32_t t = t0 + k * 100u;
        uint32_t u;
        for (u = 1; u < 100; u += 7) chair_update(&c, NULL, 0, t - 100u + u);
        send_frame(&c, t, k, (uint16_t)(k + 1), 1, 3300, 1);
        CHECK(!(c.flags & AH_FLAG_SAFE));
    }
    CHECK_EQ(c.cnt.watchdog_trips, 0);
    CHECK_EQ(c.cnt.late_frames, 0);
    CHECK_EQ(c.cnt.frames_ok, 20);
}

static void test_stop(void)
{
    chair_t c;
    harness_t h;
    ah_msg_t r;
    setup(&c, &h, 0);
    send_frame(&c, 10, 5, 1, 255, 3900, 255);
    h.tx_n = 0;
    send_empty(&c, 20, AH_MSG_STOP);
    CHECK(c.flags & AH_FLAG_SAFE);
    CHECK(c.flags & AH_FLAG_STOPPED);
    CHECK_EQ(c.safe_reason, AH_SAFE_STOP);
    CHECK_EQ(c.out.motors[0], 0);
    CHECK_EQ(c.out.fans[7], 0);
    CHECK_EQ(c.out.temp_target_cc, AH_TEMP_NEUTRAL_CC);
    CHECK_EQ(h.events[CHAIR_EV_STOP], 1);
    CHECK_EQ(replies(&h, &r), 1);
    CHECK_EQ(r.type, AH_MSG_STATUS);
    CHECK(r.u.status.flags & AH_FLAG_STOPPED);
    chair_update(&c, NULL, 0, 2000);
    CHECK_EQ(c.cnt.watchdog_trips, 0); /* already safe */
    send_frame(&c, 2001, 6, 2, 3, 3300, 4);
    CHECK(!(c.flags & (AH_FLAG_SAFE | AH_FLAG_STOPPED)));
}

static void test_temperature_clamp(void)
{
    chair_t c;
    harness_t h;
    setup(&c, &h, 0);
    send_frame(&c, 1, 0, 1, 0, 5500, 0);
    CHECK_EQ(c.out.temp_target_cc, AH_TEMP_MAX_CC);
    send_frame(&c, 2, 1, 2, 0, -4000, 0);
    CHECK_EQ(c.out.temp_target_cc, AH_TEMP_MIN_CC);
    send_frame(&c, 3, 2, 3, 0, 3456, 0);
    CHECK_EQ(c.out.temp_target_cc, 3456);
    CHECK_EQ(chair_clamp_temp(32767), AH_TEMP_MAX_CC);
    CHECK_EQ(chair_clamp_temp(-32768), AH_TEMP_MIN_CC);
    CHECK_EQ(chair_temp_drive(AH_TEMP_NEUTRAL_CC), 0);
    CHECK_EQ(chair_temp_drive(AH_TEMP_MAX_CC), 255);
    CHECK_EQ(chair_temp_drive(AH_TEMP_MIN_CC), -255);
    CHECK_EQ(chair_temp_drive(32000), 255);
    CHECK(chair_temp_drive(3500) > 0 && chair_temp_drive(3500) < 255);
    CHECK(chair_temp_drive(3000) < 0 && chair_temp_drive(3000) > -255);
}

static void test_temperature_slew(void)
{
    chair_t c;
    harness_t h;
    uint32_t t;
    int16_t prev;
    int32_t max_step_100ms = 0;
    int16_t at_100ms_ago[100];
    setup(&c, &h, 0);
    send_frame(&c, 0, 0, 0, 0, 9000, 0);
    prev = c.out.temp_setpoint_cc;
    for (t = 0; t < 100; t++) at_100ms_ago[t] = prev;
    for (t = 1; t <= 9000; t++) {
        if (t % 100 == 0) send_frame(&c, t, t / 100, (uint16_t)(t / 100), 0, 9000, 0); /* target clamps to max */
        else chair_update(&c, NULL, 0, t);
        CHECK(c.out.temp_setpoint_cc >= prev); /* monotone towards the target */
        CHECK(c.out.temp_setpoint_cc <= AH_TEMP_MAX_CC);
        {
            int32_t d = c.out.temp_setpoint_cc - at_100ms_ago[t % 100];
            if (d > max_step_100ms) max_step_100ms = d;
            at_100ms_ago[t % 100] = c.out.temp_setpoint_cc;
        }
        prev = c.out.temp_setpoint_cc;
        if (t == 1000) CHECK_EQ(c.out.temp_setpoint_cc, AH_TEMP_NEUTRAL_CC + AH_TEMP_RATE_CC_PER_S);
        if (t == 3000) CHECK_EQ(c.out.temp_setpoint_cc, AH_TEMP_NEUTRAL_CC + 3 * AH_TEMP_RATE_CC_PER_S);
    }
    /* 100 ms of slew moves at most rate/10 (+1 for rounding to whole centi-degrees) */
    CHECK(max_step_100ms <= AH_TEMP_RATE_CC_PER_S / 10 + 1);
    CHECK_EQ(c.out.temp_setpoint_cc, AH_TEMP_MAX_CC);
    CHECK(!(c.flags & AH_FLAG_RAMPING));
    /* the watchdog sends the target back to neutral; the setpoint follows at the same rate */
    chair_update(&c, NULL, 0, 9000 + AH_WATCHDOG_MS);
    CHECK_EQ(c.out.temp_target_cc, AH_TEMP_NEUTRAL_CC);
    chair_update(&c, NULL, 0, 9000 + AH_WATCHDOG_MS + 500);
    CHECK_EQ(c.out.temp_setpoint_cc, AH_TEMP_MAX_CC - AH_TEMP_RATE_CC_PER_S / 2);
    CHECK(c.flags & AH_FLAG_RAMPING);
    /* a huge gap between updates is bounded, not overflowed */
    chair_update(&c, NULL, 0, 9000 + AH_WATCHDOG_MS + 500 + 4000000000u);
    CHECK_EQ(c.out.temp_setpoint_cc, AH_TEMP_NEUTRAL_CC);
}

static void test_sequence_tracking(void)
{
    chair_t c;
    harness_t h;
    setup(&c, &h, 0);
    send_frame(&c, 0, 10, 100, 1, 3300, 0);
    send_frame(&c, 100, 11, 101, 2, 3300, 0);
    send_frame(&c, 150, 11, 101, 3, 3300, 0); /* duplicate */
    CHECK_EQ(c.cnt.stale_frames, 1);
    CHECK_EQ(c.out.motors[0], 2);
    CHECK_EQ(h.last_rx_error, AH_ERR_STALE);
    send_frame(&c, 160, 9, 99, 4, 3300, 0); /* older */
    CHECK_EQ(c.cnt.stale_frames, 2);
    send_frame(&c, 200, 15, 105, 5, 3300, 0); /* three lost in between */
    CHECK_EQ(c.cnt.seq_gaps, 3);
    CHECK_EQ(c.out.motors[0], 5);
    send_frame(&c, 400, 16, 106, 6, 3300, 0); /* 200 ms after the previous one */
    CHECK_EQ(c.cnt.late_frames, 1);
    send_frame(&c, 500, 17, 0xFFFFu, 7, 3300, 0); /* far behind in serial-number arithmetic */
    CHECK_EQ(c.cnt.stale_frames, 3);
    send_empty(&c, 510, AH_MSG_HELLO_REQ); /* a new host session may restart at any number */
    send_frame(&c, 520, 0, 3, 8, 3300, 0);
    CHECK_EQ(c.out.motors[0], 8);
    send_frame(&c, 600, 1, 4, 9, 3300, 0);
    CHECK_EQ(c.cnt.frames_ok, 6);
    /* wrap-around of the sequence number is normal */
    send_frame(&c, 700, 2, 0xFFFFu, 1, 3300, 0);
    CHECK_EQ(c.cnt.stale_frames, 4); /* 0xFFFF is behind 4 */
    send_empty(&c, 710, AH_MSG_HELLO_REQ);
    send_frame(&c, 720, 2, 0xFFFFu, 1, 3300, 0);
    send_frame(&c, 800, 3, 0x0000u, 2, 3300, 0);
    CHECK_EQ(c.out.motors[0], 2);
    CHECK_EQ(c.cnt.stale_frames, 4);
}

static void test_wrong_direction_and_overflow(void)
{
    chair_t c;
    harness_t h;
    ah_msg_t m;
    uint8_t w[AH_MAX_ENCODED + 1];
    uint8_t junk[1000];
    size_t n;
    setup(&c, &h, 0);
    memset(&m, 0, sizeof m);
    m.type = AH_MSG_HELLO;
    n = wire_of(&m, w, sizeof w);
    chair_update(&c, w, n, 1);
    CHECK_EQ(c.parser.cnt.type_errors, 1);
    CHECK_EQ(h.last_rx_error, AH_ERR_TYPE);
    memset(junk, 0x5A, sizeof junk);
    chair_update(&c, junk, sizeof junk, 2);
    CHECK_EQ(c.parser.cnt.overflows, 0); /* counted at the delimiter */
    CHECK(c.parser.n <= AH_MAX_ENCODED);
    send_frame(&c, 3, 1, 1, 42, 3300, 0); /* its delimiter ends the oversized frame; the frame is lost */
    CHECK_EQ(c.parser.cnt.overflows, 1);
    CHECK_EQ(c.cnt.frames_ok, 0);
    send_frame(&c, 4, 2, 2, 43, 3300, 0);
    CHECK_EQ(c.cnt.frames_ok, 1);
    CHECK_EQ(c.out.motors[0], 43);
}

/* Random bytes in random chunks: nothing crashes, the buffer stays bounded, counters add up. */
static void fuzz_random_bytes(uint32_t rounds)
{
    chair_t c;
    harness_t h;
    uint32_t r, t = 0;
    uint32_t before;
    setup(&c, &h, 0);
    for (r = 0; r < rounds; r++) {
        size_t n = 1 + rnd_below(300), i;
        uint8_t *buf = (uint8_t *)malloc(n); /* exact size: ASan flags any over-read */
        int zero_bias = (int)rnd_below(4);
        for (i = 0; i < n; i++) buf[i] = (zero_bias == 0 && rnd_below(20) == 0) ? 0 : (uint8_t)rnd();
        t += rnd_below(5);
        chair_update(&c, buf, n, t);
        free(buf);
        h.tx_n = 0;
        if (!CHECK(c.parser.n <= AH_MAX_ENCODED)) break;
    }
    before = c.parser.cnt.crc_errors + c.parser.cnt.length_errors + c.parser.cnt.overflows;
    CHECK(before > 0);
    printf("fuzz random: %u chunks, crc %lu length %lu overflow %lu version %lu type %lu ok %lu\n", (unsigned)rounds,
           (unsigned long)c.parser.cnt.crc_errors, (unsigned long)c.parser.cnt.length_errors,
           (unsigned long)c.parser.cnt.overflows, (unsigned long)c.parser.cnt.version_errors,
           (unsigned long)c.parser.cnt.type_errors, (unsigned long)c.parser.cnt.packets_ok);
}

/* A stream of valid frames, mangled: bit flips, truncations, garbage between frames. Every frame
 * the chair applies must be one of the originals, intact (its content matches its sequence number). */
static void fuzz_corrupted_stream(uint32_t frames)
{
    chair_t c;
    harness_t h;
    uint32_t k, t = 0, flipped = 0, truncated = 0, garbage = 0, intact = 0;
    setup(&c, &h, 0);
    h.check_consistency = 1;
    for (k = 1; k <= frames; k++) {
        ah_msg_t m;
        uint8_t w[AH_MAX_ENCODED + 1];
        uint8_t *buf;
        size_t n, i, off = 0;
        uint32_t mode = rnd_below(8);
        uint16_t seq = (uint16_t)k;
        memset(&m, 0, sizeof m);
        m.type = AH_MSG_FRAME;
        m.u.frame.tick = (uint32_t)seq * 2u;
        m.u.frame.seq = seq;
        for (i = 0; i < AH_N_MOTORS; i++) m.u.frame.motors[i] = pattern_motor(seq, (unsigned)i);
        for (i = 0; i < AH_N_FANS; i++) m.u.frame.fans[i] = pattern_fan(seq, (unsigned)i);
        m.u.frame.temp_cc = pattern_temp(seq);
        n = wire_of(&m, w, sizeof w);
        if (mode == 0) { /* one bit flipped somewhere before the delimiter */
            w[rnd_below((uint32_t)n - 1u)] ^= (uint8_t)(1u << rnd_below(8));
            flipped++;
        } else if (mode == 1) { /* cut short, delimiter kept */
            size_t keep = 1 + rnd_below((uint32_t)n - 2u);
            w[keep] = 0;
            n = keep + 1;
            truncated++;
        } else if (mode == 2) { /* cut short, delimiter lost: runs into the next frame */
            n = 1 + rnd_below((uint32_t)n - 2u);
            truncated++;
        } else {
            intact++;
        }
        buf = (uint8_t *)malloc(n + 40);
        if (mode == 3) { /* garbage (with or without a delimiter) before the frame */
            size_t g = 1 + rnd_below(39);
            for (i = 0; i < g; i++) buf[i] = (uint8_t)rnd();
            off = g;
            garbage++;
        }
        memcpy(buf + off, w, n);
        t += 100;
        {
            size_t pos = 0;
            while (pos < off + n) { /* arbitrary chunking */
                size_t step = 1 + rnd_below(64);
                if (step > off + n - pos) step = off + n - pos;
                chair_update(&c, buf + pos, step, t);
                pos += step;
            }
        }
        free(buf);
        h.tx_n = 0;
    }
    CHECK_EQ(h.inconsistent, 0);
    CHECK(c.cnt.frames_ok > 0);
    CHECK(c.parser.cnt.crc_errors > 0);
    CHECK(c.parser.cnt.length_errors > 0);
    CHECK(c.cnt.frames_ok >= intact / 2);
    CHECK(c.cnt.frames_ok <= frames);
    printf("fuzz corrupted: %u frames (%u flipped, %u truncated, %u with garbage), applied %lu intact, "
           "crc %lu length %lu overflow %lu stale %lu gaps %lu\n",
           (unsigned)frames, (unsigned)flipped, (unsigned)truncated, (unsigned)garbage, (unsigned long)c.cnt.frames_ok,
           (unsigned long)c.parser.cnt.crc_errors, (unsigned long)c.parser.cnt.length_errors,
           (unsigned long)c.parser.cnt.overflows, (unsigned long)c.cnt.stale_frames, (unsigned long)c.cnt.seq_gaps);
}

int main(int argc, char **argv)
{
    uint32_t rounds = 20000;
    if (argc < 2) {
        fprintf(stderr, "usage: %s VECTORS_FILE [FUZZ_ROUNDS]\n", argv[0]);
        return 2;
    }
    if (argc > 2) rounds = (uint32_t)strtoul(argv[2], NULL, 10);
    test_vectors(argv[1]);
    test_boot_and_hello();
    test_frame_applied_whole();
    test_watchdog();
    test_watchdog_across_millis_wrap();
    test_stop();
    test_temperature_clamp();
    test_temperature_slew();
    test_sequence_tracking();
    test_wrong_direction_and_overflow();
    fuzz_random_bytes(rounds);
    fuzz_corrupted_stream(rounds);
    printf("%d checks, %d failed\n", g_checks, g_failures);
    return g_failures ? 1 : 0;
}
