/* BUG, deep: a parser whose error path is reached only after particular answers in order.
 * The host asks `1FGET P` ten times, the same commands whatever it reads (so the wire shows
 * nothing of its state), and keeps a recovery state across answers: an `ERR` answer puts it
 * in `recovering`; then an answer with a byte no GCL answer has (a control byte or one above
 * 0x7e) in `resyncing`; then a line longer than 80 bytes in `buffered`; and there the next
 * `ERR n` is taken as an index into a 16-entry table once its value passes a check
 * (n > 1000000): a bounds error that writes far outside the table. Plausible bug: 'an error
 * code after a resync is a slot of the retry table'.
 * Expected finding, only with those four misbehaviours in that order (err-bits, garbage,
 * overlong-line, err-bits of 2^31, 2^32-1 or 20 digits): one crash, SIGSEGV in
 * `retry_slot`. Built with afl-cc it writes its edges to the map of __AFL_SHM_ID, and each
 * state reached is new code: `gcl fuzz host` guided by coverage keeps each step
 * (harness/tests/fuzz_host.rs). Every read has a 1 s deadline; it exits 0 at the end.
 * Built with -DSHALLOW_TOO it has a second bug with the same signal: a line longer than 80
 * bytes while `recovering` is logged through a null pointer (SIGSEGV in `log_overflow`), so
 * err-bits then overlong-line, the deep schedule without its garbage, crashes too, in
 * shallower code (fuzz_host_coverage.rs: minimization keeps the deep bug's edges). */
#define _GNU_SOURCE
#include "../host_mutants/gclhost.h"

static char answer[8192];
static volatile unsigned char table[16];

/* Reads an answer up to its prompt (or 1 s of silence); its length. */
static size_t read_answer(int fd) {
    size_t n = 0;
    int c;
    while ((c = gcl_getc(fd, 1000)) >= 0 && n + 1 < sizeof answer) {
        answer[n++] = (char)c;
        answer[n] = 0;
        if (n >= 3 && memcmp(answer + n - 3, "=> ", 3) == 0) break;
    }
    answer[n] = 0;
    return n;
}

/* The error code of an `ERR n` answer, or -1. */
static long err_code(size_t n) {
    const char *e = memmem(answer, n, "ERR ", 4);
    return e ? strtol(e + 4, NULL, 10) : -1;
}

static int has_foreign_byte(size_t n) {
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)answer[i];
        if ((c < 0x20 && c != '\r' && c != '\n') || c > 0x7e) return 1;
    }
    return 0;
}

static int has_long_line(size_t n) {
    size_t run = 0;
    for (size_t i = 0; i < n; i++) {
        run = (answer[i] == '\r' || answer[i] == '\n') ? 0 : run + 1;
        if (run > 80) return 1;
    }
    return 0;
}

/* The bug: an error code taken as a slot of the retry table. */
__attribute__((noinline)) static void retry_slot(long code) {
    table[code] = 1;
}

#ifdef SHALLOW_TOO
static char *volatile overflow_log;

/* The second bug: an overlong line logged before the log is made. */
__attribute__((noinline)) static void log_overflow(size_t n) {
    overflow_log[n] = 0;
}
#endif

int main(int argc, char **argv) {
    int fd = gcl_open(argc, argv);
    enum { IDLE, RECOVERING, RESYNCING, BUFFERED } state = IDLE;
    if (write(fd, "\x03", 1) != 1) return 1;
    read_answer(fd);
    for (int i = 0; i < 10; i++) {
        gcl_send_line(fd, "1FGET P");
        size_t n = read_answer(fd);
        long code = err_code(n);
        switch (state) {
        case IDLE:
            if (code >= 0) state = RECOVERING;
            break;
        case RECOVERING:
            if (has_foreign_byte(n)) state = RESYNCING;
#ifdef SHALLOW_TOO
            else if (has_long_line(n)) log_overflow(n);
#endif
            break;
        case RESYNCING:
            if (has_long_line(n)) state = BUFFERED;
            break;
        case BUFFERED:
            if (code > 1000000) retry_slot(code);
            break;
        }
    }
    return 0;
}
