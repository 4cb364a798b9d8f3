# checks.sh - the helpers the end-to-end scripts share (sourced): a pass/fail count, check, and
# expect_error for bad input (non-zero exit, exactly one 'fluidsurf: error:' line matching).
pass=0; fail=0
ok()   { pass=$((pass + 1)); }
bad()  { fail=$((fail + 1)); echo "FAIL: $*" >&2; }
check() { local what=$1; shift; if "$@"; then ok; else bad "$what"; fi; }
# expect_error WHAT PATTERN CMD...: non-zero exit, one 'fluidsurf: error:' line matching PATTERN
expect_error() {
    local what=$1 pattern=$2; shift 2
    local out rc
    out=$("$@" 2>&1 >/dev/null); rc=$?
    if [ $rc -eq 0 ]; then bad "$what: exit code 0"; return; fi
    if ! grep -q -- "$pattern" <<<"$out"; then bad "$what: message '$out' lacks '$pattern'"; return; fi
    if [ "$(grep -c 'fluidsurf: error:' <<<"$out")" -ne 1 ]; then bad "$what: not exactly one error line: $out"; return; fi
    ok
}
# signal_after SIGNAL SECONDS ERRFILE CMD...: CMD in the background (stderr to ERRFILE), sent
# SIGNAL after SECONDS; its exit code in rc
signal_after() {
    local sig=$1 secs=$2 err=$3; shift 3
    "$@" 2>"$err" &
    local pid=$!
    sleep "$secs"
    kill -"$sig" $pid
    wait $pid
    rc=$?
}
# signal_when_written SIGNAL FILE ERRFILE CMD...: CMD in the background (stderr to ERRFILE), sent
# SIGNAL as soon as FILE exists (polled every 10 ms; after 60 s, sent anyway): mid-run however
# fast the machine, where a fixed delay could come after the end. Its exit code in rc.
signal_when_written() {
    local sig=$1 file=$2 err=$3; shift 3
    "$@" 2>"$err" &
    local pid=$! waited=0
    while [ ! -e "$file" ] && [ $waited -lt 6000 ]; do
        sleep 0.01
        waited=$((waited + 1))
    done
    kill -"$sig" $pid
    wait $pid
    rc=$?
}
