/* A small C host for GCL over a serial port (a pty here), shared by the C host mutants.
 * The port's path is argv[1] or GCL_PORT. Every read has a deadline. */
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <unistd.h>

static int gcl_open(int argc, char **argv) {
    const char *path = argc > 1 ? argv[1] : getenv("GCL_PORT");
    int fd = path ? open(path, O_RDWR | O_NOCTTY) : -1;
    if (fd < 0) { perror("open port"); exit(1); }
    struct termios t;
    tcgetattr(fd, &t);
    cfmakeraw(&t);
    tcsetattr(fd, TCSANOW, &t);
    return fd;
}

/* One byte within ms milliseconds; -1 on timeout or a closed line. */
static int gcl_getc(int fd, int ms) {
    struct pollfd p = {fd, POLLIN, 0};
    unsigned char c;
    if (poll(&p, 1, ms) <= 0 || read(fd, &c, 1) != 1) return -1;
    return c;
}

/* The line, then its CR in a write of its own a moment later, as many hosts send them: the
 * hand echoes the line as it comes and answers the CR in a piece of its own. */
static void gcl_send(int fd, const char *line) {
    if (write(fd, line, strlen(line)) < 0) { perror("write"); exit(1); }
    usleep(5000);
    if (write(fd, "\r", 1) < 0) { perror("write"); exit(1); }
}

/* The line and its CR in one write: the hand takes them together, so the answers it counts
 * (where a schedule's misbehaviours land) are the same from run to run. */
static void gcl_send_line(int fd, const char *line) {
    char buf[512];
    int n = snprintf(buf, sizeof buf, "%s\r", line);
    if (n < 0 || (size_t)n >= sizeof buf || write(fd, buf, (size_t)n) != n) { perror("write"); exit(1); }
}

/* Skips bytes up to and including the prompt; 0 on success, -1 on timeout. */
static int gcl_prompt(int fd) {
    int state = 0, c;
    while ((c = gcl_getc(fd, 1000)) >= 0) {
        state = (c == '=') ? 1 : (state == 1 && c == '>') ? 2 : (state == 2 && c == ' ') ? 3 : 0;
        if (state == 3) return 0;
    }
    return -1;
}

static const char *gcl_scenario[] = {"HI", "FGET DP", "1M 5000", "1FGET P", "C", "O", "FGET P", "2M 1000", "123FGET P", 0};
