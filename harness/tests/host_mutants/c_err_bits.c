/* Mutant: the text of ERR n comes from a table indexed by n's highest bit.
 * Plausible bug: the table has the 13 documented bits; an unusual bit reads past its end.
 * Expected finding: crash (AddressSanitizer global-buffer-overflow). */
#include "gclhost.h"

static const char *status_text[13] = {"", "", "motor not initialized", "", "", "unknown command",
    "unknown parameter", "invalid value", "read-only", "", "too many arguments",
    "invalid header", "no prefix allowed"};

int main(int argc, char **argv) {
    int fd = gcl_open(argc, argv);
    write(fd, "\x03", 1);
    if (gcl_prompt(fd)) return 1;
    for (const char **l = gcl_scenario; *l; l++) {
        char buf[256];
        int n = 0, c;
        gcl_send(fd, *l);
        while (n < 255 && (c = gcl_getc(fd, 1000)) >= 0) {
            buf[n++] = (char)c;
            if (n >= 3 && memcmp(buf + n - 3, "=> ", 3) == 0) break;
        }
        buf[n] = 0;
        char *err = strstr(buf, "ERR ");
        if (err) {
            unsigned long code = strtoul(err + 4, 0, 10), bit = 0;
            while (code >> (bit + 1)) bit++;
            fprintf(stderr, "%s refused: %s\n", *l, status_text[bit]);
            return 1;
        }
        if (c < 0) return 1;
    }
    return 0;
}
