/* Mutant: answer lines go into a fixed 64-byte buffer with no bound check.
 * Plausible bug: 'a GCL line is short'; an overlong line overflows the stack buffer.
 * Expected finding: crash (AddressSanitizer stack-buffer-overflow). */
#include "gclhost.h"

/* Reads one line ending in LF CR into line; returns its length, -1 at the prompt or on timeout. */
static int read_line(int fd, char *line) {
    int n = 0, c;
    while ((c = gcl_getc(fd, 1000)) >= 0) {
        if (c == '\n') continue;
        if (c == '\r') { line[n] = 0; return n; }
        line[n++] = (char)c;
        if (n == 3 && memcmp(line, "=> ", 3) == 0) return -1;
    }
    return -1;
}

int main(int argc, char **argv) {
    int fd = gcl_open(argc, argv);
    write(fd, "\x03", 1);
    if (gcl_prompt(fd)) return 1;
    for (const char **l = gcl_scenario; *l; l++) {
        char line[64];
        gcl_send(fd, *l);
        while (read_line(fd, line) >= 0) {
            if (strncmp(line, "ERR", 3) == 0) { fprintf(stderr, "%s: %s\n", *l, line); return 1; }
        }
    }
    return 0;
}
