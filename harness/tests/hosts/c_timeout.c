/* CORRECT: a C host whose every read has one long deadline (15 s unless argv[2] gives the
 * seconds), as Barrett's C++ driver has. It runs the supervisory scenario; a cut, garbled or
 * refused answer, or silence, is reported on one line and it exits 1.
 * Usage: c_timeout [PORT] [SECONDS] (PORT default: $GCL_PORT).
 * Expected: no finding from `gcl fuzz host` with default options; a pass from check-host. */
#include "../host_mutants/gclhost.h"

static int timeout_ms = 15000;

/* The answer to `line` up to its prompt into buf; 0, or -1 on timeout, overflow or a bad echo. */
static int ask(int fd, const char *line, char *buf, size_t cap) {
    size_t n = 0;
    gcl_send(fd, line);
    for (;;) {
        int c = gcl_getc(fd, timeout_ms);
        if (c < 0 || n + 1 >= cap) return -1;
        buf[n++] = (char)c;
        buf[n] = 0;
        if (n >= 3 && memcmp(buf + n - 3, "=> ", 3) == 0) break;
    }
    size_t len = strlen(line);
    if (strncmp(buf, line, len) != 0 || buf[len] != '\n') return -1;
    return strstr(buf, "ERR ") ? -1 : 0;
}

int main(int argc, char **argv) {
    int fd = gcl_open(argc, argv);
    if (argc > 2) timeout_ms = atoi(argv[2]) * 1000;
    char buf[4096];
    if (write(fd, "\x03", 1) != 1) return 1;
    for (;;) { /* up to the prompt after ^C */
        int c = gcl_getc(fd, timeout_ms);
        if (c < 0) { fprintf(stderr, "host: no prompt after ^C\n"); return 1; }
        if (c == ' ') break;
    }
    for (int i = 0; gcl_scenario[i]; i++) {
        tcflush(fd, TCIFLUSH);
        if (ask(fd, gcl_scenario[i], buf, sizeof buf) != 0) {
            fprintf(stderr, "host: %s: no good answer\n", gcl_scenario[i]);
            return 1;
        }
    }
    close(fd);
    return 0;
}
