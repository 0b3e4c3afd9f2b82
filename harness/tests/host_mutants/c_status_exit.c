/* Mutant: the program's exit status is the last status the hand reported.
 * Plausible bug: 'main returns the error code'; ERR 65535 or ERR -1 becomes exit 255.
 * Expected finding: exit-code (outside 0,1). */
#include "gclhost.h"

int main(int argc, char **argv) {
    int fd = gcl_open(argc, argv);
    long status = 0;
    write(fd, "\x03", 1);
    if (gcl_prompt(fd)) return 1;
    for (const char **l = gcl_scenario; *l && status == 0; l++) {
        char buf[256];
        int n = 0, c = 0;
        gcl_send(fd, *l);
        while (n < 255 && (c = gcl_getc(fd, 1000)) >= 0) {
            buf[n++] = (char)c;
            if (n >= 3 && memcmp(buf + n - 3, "=> ", 3) == 0) break;
        }
        buf[n] = 0;
        char *err = strstr(buf, "ERR ");
        if (err) status = strtol(err + 4, 0, 10);
        if (c < 0) return 1;
    }
    return (int)(status & 0xff) ? (int)(status & 0xff) : (status != 0);
}
