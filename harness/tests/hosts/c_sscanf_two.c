/* BUG: two functions each read an answer's values with sscanf("%s") into a word too small
 * for them, as Barrett's API did in HandPGet and HandGet: hand_pget into 8 bytes on the
 * stack, hand_get into 8 bytes on the heap. Plausible bug: 'a value is at most 7 digits'.
 * Expected findings: two crashes, one per function, `asan stack-buffer-overflow in
 * hand_pget` and `asan heap-buffer-overflow in hand_get`, each once, never signed by
 * sscanf's interceptor (`scanf_common`). */
#include "../host_mutants/gclhost.h"

static char answer[8192];

/* Sends line and reads its answer up to the prompt; the value line (after the echo), or NULL. */
static const char *ask(int fd, const char *line) {
    size_t n = 0;
    int c;
    gcl_send_line(fd, line);
    while ((c = gcl_getc(fd, 1000)) >= 0 && n + 1 < sizeof answer) {
        answer[n++] = (char)c;
        answer[n] = 0;
        if (n >= 3 && memcmp(answer + n - 3, "=> ", 3) == 0) {
            const char *values = strstr(answer, "\n\r");
            return values ? values + 2 : answer + n;
        }
    }
    return NULL;
}

/* A parameter of one motor (the API's HandPGet): the first value, into a stack word. */
static long hand_pget(int fd, const char *line) {
    char word[8];
    const char *v = ask(fd, line);
    if (!v || sscanf(v, "%s", word) != 1) return -1;
    return strtol(word, NULL, 10);
}

/* A parameter of every motor (the API's HandGet): the first value, into a heap word. */
static long hand_get(int fd, const char *line) {
    char *word = malloc(8);
    const char *v = ask(fd, line);
    long x = (v && sscanf(v, "%s", word) == 1) ? strtol(word, NULL, 10) : -1;
    free(word);
    return x;
}

int main(int argc, char **argv) {
    int fd = gcl_open(argc, argv);
    if (write(fd, "\x03", 1) != 1 || gcl_prompt(fd)) return 1;
    if (!ask(fd, "HI")) return 1;
    for (int i = 0; i < 3; i++) {
        if (hand_pget(fd, "1FGET P") < 0) { fprintf(stderr, "host: 1FGET P: no value\n"); return 1; }
        if (hand_get(fd, "FGET DP") < 0) { fprintf(stderr, "host: FGET DP: no value\n"); return 1; }
    }
    return 0;
}
