/* BUG: the first word of each answer line is read with sscanf("%s") into an 8-byte word
 * on the stack. Plausible bug: 'a GCL value is a short number'; a longer word (an overlong or
 * garbled line) overflows it inside sscanf.
 * Expected finding: one crash, `asan stack-buffer-overflow in first_word` (the host's own
 * function; sscanf's interceptor in the message), whichever line overflows it. */
#include "../host_mutants/gclhost.h"

/* The answer to the last command up to its prompt into buf; 0, or -1 on timeout. */
static int read_answer(int fd, char *buf, size_t cap) {
    size_t n = 0;
    int c;
    while ((c = gcl_getc(fd, 1000)) >= 0 && n + 1 < cap) {
        buf[n++] = (char)c;
        buf[n] = 0;
        if (n >= 3 && memcmp(buf + n - 3, "=> ", 3) == 0) return 0;
    }
    return -1;
}

/* The first word of the value line (after the echo) of an answer. */
static int first_word(const char *answer) {
    char word[8];
    const char *values = strstr(answer, "\n\r");
    if (!values || sscanf(values + 2, "%s", word) != 1) return -1;
    return word[0] == 'E' ? -1 : 0;
}

int main(int argc, char **argv) {
    int fd = gcl_open(argc, argv);
    static char buf[8192];
    if (write(fd, "\x03", 1) != 1 || gcl_prompt(fd)) return 1;
    for (int i = 0; gcl_scenario[i]; i++) {
        gcl_send_line(fd, gcl_scenario[i]);
        if (read_answer(fd, buf, sizeof buf) != 0) { fprintf(stderr, "host: %s: no answer\n", gcl_scenario[i]); return 1; }
        if (first_word(buf) != 0) { fprintf(stderr, "host: %s: refused\n", gcl_scenario[i]); return 1; }
    }
    return 0;
}
