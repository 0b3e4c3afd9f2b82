// One scenario against the hand on argv[1] (or GCL_PORT): what gcl check-host and gcl fuzz
// host run. Exit 0 when it ran, 1 when the hand was broken and the library said so.
#include <cstdio>
#include <cstdlib>

#include "bh8host.hpp"

int main(int argc, char** argv) {
    const char* port = argc > 1 ? argv[1] : std::getenv("GCL_PORT");
    if (!port) {
        std::fprintf(stderr, "usage: %s PORT\n", argv[0]);
        return 2;
    }
    try {
        bh8::Hand hand(port);
        hand.sync();
        std::printf("%s\n", hand.version().c_str());
        hand.home();
        for (long p : hand.get("P", "123")) std::printf("%ld ", p);
        std::printf("\n");
        hand.command("1M 5000");
        hand.command("C");
        return 0;
    } catch (const bh8::Error& e) {
        std::fprintf(stderr, "bh8host: %s\n", e.what());
        return 1;
    }
}
