/* BUGGY: an error nobody catches, thrown from one of two places by turns (the runs it has made
 * counted in a file of argv[2]): `send_line` on its 1st, 3rd... run, `read_line` on its 2nd,
 * 4th..., each with its own what(). It stands for a host that fails at a place that depends on
 * timing (a write or a read meeting a hung-up line), whose second run, under gdb, may throw from
 * the other place.
 * Usage: cpp_throws_by_turns PORT FOLDER.
 * Expected: its first run's crash is signed by the place that threw what that run's what()
 * says (`in send_line`): a second run under gdb that threw the same is taken before one that
 * threw from the other place. */
#include <fcntl.h>
#include <unistd.h>
#include <cstdio>
#include <stdexcept>
#include <string>

__attribute__((noinline)) static void send_line(int fd) {
    if (fd >= 0) (void)!write(fd, "\x03", 1);
    throw std::runtime_error("write: the first place");
}

__attribute__((noinline)) static void read_line(int fd) {
    if (fd >= 0) (void)!write(fd, "\x03", 1);
    throw std::runtime_error("read: the second place");
}

int main(int argc, char **argv) {
    if (argc < 3) return 2;
    std::string count = std::string(argv[2]) + "/runs";
    int n = 0;
    if (FILE *f = fopen(count.c_str(), "r")) {
        if (fscanf(f, "%d", &n) != 1) n = 0;
        fclose(f);
    }
    if (FILE *f = fopen(count.c_str(), "w")) {
        fprintf(f, "%d\n", n + 1);
        fclose(f);
    }
    int fd = open(argv[1], O_RDWR | O_NOCTTY);
    if (n % 2 == 0) send_line(fd);
    read_line(fd);
    return 0;
}
