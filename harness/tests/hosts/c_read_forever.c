/* BUG: the supervisory read has no timeout (a blocking read() until the prompt), as in a
 * public C library for the BH8. Whatever answer the hand cuts, garbles or never ends, in
 * whichever state, the host waits for ever in the same place: read_answer.
 * Usage: c_read_forever [PORT] (default: $GCL_PORT).
 * Expected: `gcl fuzz host` reports ONE hang, whose signature names read_answer. */
#include "../host_mutants/gclhost.h"

static void read_answer(int fd) {
    int state = 0;
    unsigned char c;
    while (read(fd, &c, 1) == 1) {
        state = (c == '=') ? 1 : (state == 1 && c == '>') ? 2 : (state == 2 && c == ' ') ? 3 : 0;
        if (state == 3) return;
    }
    exit(1);
}

int main(int argc, char **argv) {
    int fd = gcl_open(argc, argv);
    if (write(fd, "\x03", 1) != 1) return 1;
    read_answer(fd);
    const char *more[] = {"", "HI", "O", "M", "FGET DP", 0};
    for (int i = 0; gcl_scenario[i]; i++) {
        gcl_send(fd, gcl_scenario[i]);
        read_answer(fd);
    }
    for (int i = 0; more[i]; i++) {
        gcl_send(fd, more[i]);
        read_answer(fd);
    }
    return 0;
}
