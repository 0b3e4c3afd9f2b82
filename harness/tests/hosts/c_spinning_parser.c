/* BUG: as a vendor API does it: the caller hands each command to a parser thread and waits for
 * its answer on a condition variable without a deadline; the parser thread sends the command,
 * reads the answer up to its prompt (1 s deadline) and parses the values line. A character in
 * that line that is neither a digit, a sign nor a space is never stepped over: the parser spins
 * at 100 % CPU, and the caller waits for ever (a CR LF line end, `crlf`, puts a CR there).
 * Usage: c_spinning_parser [PORT] (default: $GCL_PORT). Build with -pthread.
 * Expected: one hang, `hang in parse_values` (the spinning thread's own frame), the waiting
 * main thread named in its message; no finding against a hand that behaves. */
#include <pthread.h>
#include "../host_mutants/gclhost.h"

static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_cond_t changed = PTHREAD_COND_INITIALIZER;
static const char *request;
static int done, failed, fd;
static long values[8];

/* The values of an answer's values line (after the echo line); spins on a stray character. */
static int parse_values(const char *answer) {
    const char *p = strchr(answer, '\n');
    int n = 0;
    if (!p) return 0;
    p++;
    if (*p == '\r') p++;
    while (*p && *p != '\n' && n < 8) {
        if ((*p >= '0' && *p <= '9') || *p == '-') {
            char *end;
            values[n++] = strtol(p, &end, 10);
            p = end;
        } else if (*p == ' ') {
            p++;
        }
        /* anything else: not stepped over */
    }
    return n;
}

static int ask(const char *line, char *buf, size_t cap) {
    size_t n = 0;
    gcl_send_line(fd, line);
    for (;;) {
        int c = gcl_getc(fd, 1000);
        if (c < 0 || n + 1 >= cap) return -1;
        buf[n++] = (char)c;
        buf[n] = 0;
        if (n >= 3 && memcmp(buf + n - 3, "=> ", 3) == 0) return 0;
    }
}

static void *parser(void *arg) {
    (void)arg;
    char buf[4096];
    for (;;) {
        pthread_mutex_lock(&lock);
        while (!request) pthread_cond_wait(&changed, &lock);
        const char *line = request;
        pthread_mutex_unlock(&lock);
        int bad = ask(line, buf, sizeof buf) != 0 || strstr(buf, "ERR ") != NULL;
        if (!bad && strstr(line, "FGET")) parse_values(buf);
        pthread_mutex_lock(&lock);
        request = NULL;
        done = 1;
        failed = bad;
        pthread_cond_broadcast(&changed);
        pthread_mutex_unlock(&lock);
    }
    return NULL;
}

/* Hands `line` to the parser and waits for it, without a deadline. */
static int command(const char *line) {
    pthread_mutex_lock(&lock);
    request = line;
    done = 0;
    pthread_cond_broadcast(&changed);
    while (!done) pthread_cond_wait(&changed, &lock);
    int bad = failed;
    pthread_mutex_unlock(&lock);
    return bad ? -1 : 0;
}

int main(int argc, char **argv) {
    fd = gcl_open(argc, argv);
    if (write(fd, "\x03", 1) != 1 || gcl_prompt(fd) != 0) {
        fprintf(stderr, "host: no prompt after ^C\n");
        return 1;
    }
    pthread_t t;
    pthread_create(&t, NULL, parser, NULL);
    for (int i = 0; gcl_scenario[i]; i++) {
        if (command(gcl_scenario[i]) != 0) {
            fprintf(stderr, "host: %s: no good answer\n", gcl_scenario[i]);
            return 1;
        }
    }
    close(fd);
    return 0;
}
