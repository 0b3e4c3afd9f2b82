/* CORRECT, but it opens only a fixed device path, as a vendor API that takes a port number
 * does: argv[1] must name `.../ttyUSB<k>` (`gcl fuzz host --link DIR/ttyUSB{slot}` gives each
 * slot's host its own). Every read has a deadline (argv[2] seconds, default 1). With argv[3], a
 * folder: while it runs it notes itself there (a file named by its pid), and when it starts it
 * appends to argv[3]/alive.log how many such hosts are alive, itself included, so a test sees
 * how many hosts ran at once.
 * Usage: c_fixed_path PORT [SECONDS [FOLDER]].
 * Expected: no finding from `gcl fuzz host --link` at any --jobs, at most --jobs alive at once,
 * calibration and confirmations included; never two hosts on one port. */
#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include "../host_mutants/gclhost.h"

static int timeout_ms = 1000;
static char note[4096];

/* How many hosts noted in `dir` are alive. */
static int alive(const char *dir) {
    DIR *d = opendir(dir);
    int n = 0;
    struct dirent *e;
    if (!d) return 0;
    while ((e = readdir(d))) {
        char *end;
        long pid = strtol(e->d_name, &end, 10);
        if (*end == 0 && pid > 0 && (kill((pid_t)pid, 0) == 0 || errno == EPERM)) n++;
    }
    closedir(d);
    return n;
}

static void count_in(const char *dir) {
    snprintf(note, sizeof note, "%s/%d", dir, (int)getpid());
    FILE *f = fopen(note, "w");
    if (f) fclose(f);
    char log[4096];
    snprintf(log, sizeof log, "%s/alive.log", dir);
    f = fopen(log, "a");
    if (f) {
        fprintf(f, "%d\n", alive(dir));
        fclose(f);
    }
}

/* Reads up to the prompt `=> `; 0, or -1 on timeout. */
static int prompt(int fd) {
    int state = 0, c;
    while ((c = gcl_getc(fd, timeout_ms)) >= 0) {
        state = (c == '=') ? 1 : (state == 1 && c == '>') ? 2 : (state == 2 && c == ' ') ? 3 : 0;
        if (state == 3) return 0;
    }
    return -1;
}

int main(int argc, char **argv) {
    if (argc < 2) { fprintf(stderr, "usage: c_fixed_path PORT [SECONDS [FOLDER]]\n"); return 2; }
    const char *base = strrchr(argv[1], '/');
    base = base ? base + 1 : argv[1];
    if (strncmp(base, "ttyUSB", 6) != 0 || base[6] < '0' || base[6] > '9') {
        fprintf(stderr, "host: %s: only /dev/ttyUSB<k> is supported\n", argv[1]);
        return 2;
    }
    if (argc > 2) timeout_ms = atoi(argv[2]) * 1000;
    if (argc > 3) count_in(argv[3]);
    int fd = gcl_open(2, argv);
    int rc = 0;
    if (write(fd, "\x03", 1) != 1 || prompt(fd) != 0) {
        fprintf(stderr, "host: no prompt after ^C\n");
        rc = 1;
    }
    for (int i = 0; rc == 0 && gcl_scenario[i]; i++) {
        gcl_send_line(fd, gcl_scenario[i]);
        if (prompt(fd) != 0) {
            fprintf(stderr, "host: %s: no prompt\n", gcl_scenario[i]);
            rc = 1;
        }
    }
    close(fd);
    if (note[0]) unlink(note);
    return rc;
}
