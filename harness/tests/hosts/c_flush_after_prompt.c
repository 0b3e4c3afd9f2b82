/* CORRECT: a C host that reads each answer up to its prompt's `=>`, leaves the space after it,
 * and discards what is pending with tcflush(TCIFLUSH) 10 ms after that space has come, just
 * before it writes its next command (as a C library for the hand does). The space is read by
 * the flush: nothing is sent before the prompt.
 * Usage: c_flush_after_prompt [PORT] [SECONDS] (PORT default: $GCL_PORT; each read's deadline,
 * default 5 s).
 * Expected: no host-waits-for-answer violation from check-host on a paced line (the space comes
 * after the host's last read) or from `gcl fuzz host`. */
#include "../host_mutants/gclhost.h"

static int timeout_ms = 5000;

/* Reads up to `=>` (the space after it is left); 0, or -1 on timeout. */
static int up_to_prompt(int fd) {
    int prev = 0, c;
    while ((c = gcl_getc(fd, timeout_ms)) >= 0) {
        if (prev == '=' && c == '>') return 0;
        prev = c;
    }
    return -1;
}

/* Waits (without reading) for the prompt's space to come, then 10 ms, then discards it. */
static void discard_rest(int fd) {
    struct pollfd p = {fd, POLLIN, 0};
    poll(&p, 1, 1000);
    usleep(10000);
    tcflush(fd, TCIFLUSH);
}

int main(int argc, char **argv) {
    int fd = gcl_open(argc, argv);
    if (argc > 2) timeout_ms = atoi(argv[2]) * 1000;
    if (write(fd, "\x03", 1) != 1) return 1;
    if (up_to_prompt(fd) != 0) { fprintf(stderr, "host: no prompt after ^C\n"); return 1; }
    for (int i = 0; gcl_scenario[i]; i++) {
        discard_rest(fd);
        gcl_send_line(fd, gcl_scenario[i]);
        if (up_to_prompt(fd) != 0) {
            fprintf(stderr, "host: %s: no prompt\n", gcl_scenario[i]);
            return 1;
        }
    }
    close(fd);
    return 0;
}
