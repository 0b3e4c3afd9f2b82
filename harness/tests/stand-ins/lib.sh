# The stand-ins' shell helpers (harness/tests/it/docs.rs writes this file into the folder every
# documented command runs in). A stand-in uses them as `sh -c '. ./lib.sh; ...'`.

# wait_line FILE: waits (up to 30 s) until FILE holds a line.
wait_line() {
    n=0
    until [ -s "$1" ] || [ $n -ge 300 ]; do sleep 0.1; n=$((n + 1)); done
}

# serve COMMAND...: a server that prints where it listens (a pty, an address) as its first
# line: it is started, its first line printed, and it is stopped with SIGTERM; the exit code is
# its own.
serve() {
    rm -f .serve.out
    "$@" > .serve.out 2> .serve.err &
    pid=$!
    wait_line .serve.out
    head -n 1 .serve.out
    kill -TERM $pid
    wait $pid
}

# with_sim ARGS...: `gcl sim ARGS` in the background; $SIM is what it printed first (its pty
# or address). stop_sim ends it.
with_sim() {
    rm -f .sim.out
    gcl sim "$@" > .sim.out 2> /dev/null &
    sim=$!
    wait_line .sim.out
    SIM=$(head -n 1 .sim.out)
}
stop_sim() {
    kill $sim 2> /dev/null
    wait $sim 2> /dev/null
}
