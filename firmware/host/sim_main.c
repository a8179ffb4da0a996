/* The virtual chair: the portable core on a POSIX pseudo-terminal.
 *
 *   autohaptics-chair-sim [--log FILE] [--link PATH]
 *
 * Opens a pty, prints the slave device path as the first line of stdout, and runs the core with
 * a 1 ms clock (CLOCK_MONOTONIC) until SIGINT/SIGTERM/SIGHUP. Bytes are fed to the core as soon
 * as they arrive. --link maintains a symlink PATH -> the slave device, replaced atomically on
 * start, so a restarted chair appears under the same path. --log writes one JSON object per line
 * for every applied frame and every state change; t_ms is CLOCK_MONOTONIC in milliseconds
 * (microsecond resolution), taken when the core applied the frame. */
#define _XOPEN_SOURCE 600

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/select.h>
#include <sys/stat.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "chair_core.h"

typedef struct {
    int master;
    FILE *log;
} sim_t;

#define SIM_NICE (-10)

static volatile sig_atomic_t g_stop = 0;

static void on_signal(int sig)
{
    (void)sig;
    g_stop = 1;
}

static long long mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long long)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static uint32_t millis(void) { return (uint32_t)(mono_ns() / 1000000LL); }

static void log_time(FILE *f)
{
    long long ns = mono_ns();
    fprintf(f, "{\"t_ms\":%lld.%03lld", ns / 1000000LL, (ns / 1000LL) % 1000LL);
}

static void log_array(FILE *f, const char *key, const uint8_t *v, size_t n)
{
    size_t i;
    fprintf(f, ",\"%s\":[", key);
    for (i = 0; i < n; i++) fprintf(f, i ? ",%u" : "%u", (unsigned)v[i]);
    fputc(']', f);
}

static const char *safe_reason_name(uint8_t r)
{
    switch (r) {
    case AH_SAFE_BOOT: return "boot";
    case AH_SAFE_WATCHDOG: return "watchdog";
    case AH_SAFE_STOP: return "stop";
    default: return "none";
    }
}

static void log_state(FILE *f, const chair_t *c)
{
    fprintf(f, ",\"temp_target_cc\":%d,\"temp_cc\":%d,\"safe\":%s", (int)c->out.temp_target_cc,
            (int)c->out.temp_setpoint_cc, (c->flags & AH_FLAG_SAFE) ? "true" : "false");
}

static void on_event(void *ctx, chair_event_t ev, int status, const chair_t *c)
{
    sim_t *s = (sim_t *)ctx;
    FILE *f = s->log;
    if (f == NULL || ev == CHAIR_EV_TEMP) return; /* every frame line carries the setpoint */
    log_time(f);
    switch (ev) {
    case CHAIR_EV_FRAME:
        fprintf(f, ",\"ev\":\"frame\",\"tick\":%lu,\"seq\":%u", (unsigned long)c->last_tick, (unsigned)c->last_seq);
        log_array(f, "motors", c->out.motors, AH_N_MOTORS);
        log_array(f, "fans", c->out.fans, AH_N_FANS);
        break;
    case CHAIR_EV_SAFE:
    case CHAIR_EV_STOP:
        fprintf(f, ",\"ev\":\"%s\",\"reason\":\"%s\",\"last_tick\":%lu", ev == CHAIR_EV_SAFE ? "safe" : "stop",
                safe_reason_name(c->safe_reason), (unsigned long)c->last_tick);
        log_array(f, "motors", c->out.motors, AH_N_MOTORS);
        log_array(f, "fans", c->out.fans, AH_N_FANS);
        break;
    case CHAIR_EV_HELLO:
        fputs(",\"ev\":\"hello\"", f);
        break;
    case CHAIR_EV_RX_ERROR:
        fprintf(f, ",\"ev\":\"rx_error\",\"status\":\"%s\"", ah_status_name((ah_status_t)status));
        break;
    default:
        fprintf(f, ",\"ev\":\"event%d\"", (int)ev);
        break;
    }
    log_state(f, c);
    fputs("}\n", f);
}

static size_t write_host(void *ctx, const uint8_t *data, size_t n)
{
    sim_t *s = (sim_t *)ctx;
    size_t done = 0;
    while (done < n) {
        ssize_t w = write(s->master, data + done, n - done);
        if (w > 0) {
            done += (size_t)w;
        } else if (w < 0 && errno == EINTR) {
            continue;
        } else {
            break; /* EAGAIN: nobody is reading; the reply is dropped and counted */
        }
    }
    return done;
}

static int make_raw(int fd)
{
    struct termios t;
    if (tcgetattr(fd, &t) != 0) return -1;
    t.c_iflag &= ~(tcflag_t)(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL | IXON | IXOFF);
    t.c_oflag &= ~(tcflag_t)OPOST;
    t.c_lflag &= ~(tcflag_t)(ECHO | ECHONL | ICANON | ISIG | IEXTEN);
    t.c_cflag &= ~(tcflag_t)(CSIZE | PARENB);
    t.c_cflag |= (tcflag_t)CS8;
    t.c_cc[VMIN] = 1;
    t.c_cc[VTIME] = 0;
    return tcsetattr(fd, TCSANOW, &t);
}

static int replace_link(const char *link, const char *target)
{
    char tmp[4096];
    if ((size_t)snprintf(tmp, sizeof tmp, "%s.%ld.tmp", link, (long)getpid()) >= sizeof tmp) return -1;
    unlink(tmp);
    if (symlink(target, tmp) != 0) return -1;
    if (rename(tmp, link) != 0) {
        unlink(tmp);
        return -1;
    }
    return 0;
}

static void remove_link_if_ours(const char *link, const char *target)
{
    char buf[4096];
    ssize_t n = readlink(link, buf, sizeof buf - 1);
    if (n < 0) return;
    buf[n] = '\0';
    if (strcmp(buf, target) == 0) unlink(link);
}

static int usage(void)
{
    fputs("usage: autohaptics-chair-sim [--log FILE] [--link PATH]\n", stderr);
    return 2;
}

int main(int argc, char **argv)
{
    const char *log_path = NULL, *link_path = NULL;
    char slave_path[256];
    const char *name;
    int i, slave, nice_value;
    sim_t sim;
    chair_t chair;
    chair_io_t io;
    struct sigaction sa;
    long long next_tick;

    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--log") == 0 && i + 1 < argc) log_path = argv[++i];
        else if (strcmp(argv[i], "--link") == 0 && i + 1 < argc) link_path = argv[++i];
        else return usage();
    }

    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGHUP, &sa, NULL);
    signal(SIGPIPE, SIG_IGN);

    sim.log = NULL;
    sim.master = posix_openpt(O_RDWR | O_NOCTTY);
    if (sim.master < 0 || grantpt(sim.master) != 0 || unlockpt(sim.master) != 0 || (name = ptsname(sim.master)) == NULL) {
        perror("autohaptics-chair-sim: cannot open a pseudo-terminal");
        return 1;
    }
    snprintf(slave_path, sizeof slave_path, "%s", name);
    /* Hold the slave open ourselves: the master then never sees a hang-up when the host closes
     * its side, and the line discipline is raw (no echo, no CR/LF mapping) before anyone opens it. */
    slave = open(slave_path, O_RDWR | O_NOCTTY);
    if (slave < 0 || make_raw(slave) != 0) {
        perror("autohaptics-chair-sim: cannot configure the pseudo-terminal");
        return 1;
    }
    fcntl(sim.master, F_SETFL, fcntl(sim.master, F_GETFL) | O_NONBLOCK);
    /* Best effort: a real chair has its own processor; on a busy host a higher priority keeps the
     * virtual one closer to that. Without the privilege (CAP_SYS_NICE) it stays at nice 0. */
    nice_value = setpriority(PRIO_PROCESS, 0, SIM_NICE) == 0 ? SIM_NICE : getpriority(PRIO_PROCESS, 0);
    if (log_path != NULL) {
        sim.log = fopen(log_path, "a");
        if (sim.log == NULL) {
            perror(log_path);
            return 1;
        }
        setvbuf(sim.log, NULL, _IOLBF, 1 << 16);
    }
    if (link_path != NULL && replace_link(link_path, slave_path) != 0) {
        perror(link_path);
        return 1;
    }

    io.write = write_host;
    io.event = on_event;
    io.ctx = &sim;
    chair_init(&chair, &io, millis());
    if (sim.log != NULL) {
        log_time(sim.log);
        fprintf(sim.log, ",\"ev\":\"start\",\"pid\":%ld,\"pty\":\"%s\",\"watchdog_ms\":%u,\"nice\":%d", (long)getpid(),
                slave_path, (unsigned)AH_WATCHDOG_MS, nice_value);
        log_state(sim.log, &chair);
        fputs("}\n", sim.log);
    }
    printf("%s\n", slave_path);
    fflush(stdout);

    next_tick = mono_ns() + 1000000LL;
    while (!g_stop) {
        uint8_t buf[4096];
        fd_set rd;
        struct timespec ts;
        long long now = mono_ns(), wait = next_tick - now;
        if (wait < 0) wait = 0;
        ts.tv_sec = (time_t)(wait / 1000000000LL);
        ts.tv_nsec = (long)(wait % 1000000000LL);
        FD_ZERO(&rd);
        FD_SET(sim.master, &rd);
        if (pselect(sim.master + 1, &rd, NULL, NULL, &ts, NULL) > 0 && FD_ISSET(sim.master, &rd)) {
            ssize_t n = read(sim.master, buf, sizeof buf);
            if (n > 0) chair_update(&chair, buf, (size_t)n, millis());
        }
        now = mono_ns();
        if (now >= next_tick) {
            chair_update(&chair, NULL, 0, millis());
            next_tick += 1000000LL;
            if (next_tick < now) next_tick = now + 1000000LL; /* fell behind (suspended): no burst */
        }
    }

    if (sim.log != NULL) {
        log_time(sim.log);
        fputs(",\"ev\":\"exit\"", sim.log);
        log_state(sim.log, &chair);
        fputs("}\n", sim.log);
        fclose(sim.log);
    }
    if (link_path != NULL) remove_link_if_ours(link_path, slave_path);
    close(slave);
    close(sim.master);
    return 0;
}
