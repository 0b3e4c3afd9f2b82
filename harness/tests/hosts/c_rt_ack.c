/* BUG: in RealTime, the hand's acknowledgement of a control block (its feedback block,
 * '*' and 9 bytes for the loop below) is read into an 8-byte buffer, as a public C library's
 * was. The host dies in RealTime, with the hand in its loop.
 * Plausible bug: 'a block is 8 bytes' (a layout with fewer fields).
 * Expected finding: ONE crash, `asan stack-buffer-overflow in read_ack`; not a second
 * `violation: leaves-cleanly: left in RealTime` (a host that crashed did not choose how to
 * leave). */
#include "../host_mutants/gclhost.h"

#define FEEDBACK 10 /* '*' + 3 x (velocity, position high, position low) */

/* The acknowledgement of one control block; 0, or -1 on timeout. */
static int read_ack(int fd) {
    char ack[8];
    for (int n = 0; n < FEEDBACK; n++) {
        int c = gcl_getc(fd, 1000);
        if (c < 0) return -1;
        ack[n] = (char)c;
    }
    return ack[0] == '*' ? 0 : -1;
}

int main(int argc, char **argv) {
    int fd = gcl_open(argc, argv);
    if (write(fd, "\x03", 1) != 1 || gcl_prompt(fd)) return 1;
    gcl_send_line(fd, "HI");
    if (gcl_prompt(fd)) return 1;
    gcl_send_line(fd, "123FSET LCV 1 LCVC 1 LCPG 0 LFV 1 LFVC 1 LFS 0 LFAP 1 LFDP 0");
    if (gcl_prompt(fd)) return 1;
    gcl_send_line(fd, "123LOOP");
    for (int c; (c = gcl_getc(fd, 1000)) != '*';) {
        if (c < 0) { fprintf(stderr, "host: no '*' after LOOP\n"); return 1; }
    }
    for (int i = 0; i < 4; i++) {
        if (write(fd, "C\x14\x14\x14", 4) != 4) return 1;
        if (read_ack(fd) != 0) { fprintf(stderr, "host: no feedback\n"); return 1; }
    }
    if (write(fd, "\x03", 1) != 1 || gcl_prompt(fd)) return 1;
    return 0;
}
