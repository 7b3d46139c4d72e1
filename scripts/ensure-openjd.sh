# Sourced by ./run-tests: the Open Job Description test (tests/farm_openjd.rs) runs the job
# templates with the reference runner, `openjd run` (PyPI's openjd-cli). When no `openjd` is on
# PATH it is installed into a virtual environment under the user's cache (kept between runs)
# and that environment's bin is put on PATH. python3 and its venv module come from Debian's
# packages when missing. The test fails loudly without the runner, never skips.
if ! command -v openjd >/dev/null; then
    OPENJD_VENV="${XDG_CACHE_HOME:-$HOME/.cache}/reyes/openjd-venv"
    if [ ! -x "$OPENJD_VENV/bin/openjd" ]; then
        echo "openjd missing: installing openjd-cli into $OPENJD_VENV (for tests/farm_openjd.rs)" >&2
        if ! command -v python3 >/dev/null || ! python3 -m venv --help >/dev/null 2>&1 \
            || ! python3 -c 'import ensurepip' >/dev/null 2>&1; then
            if [ "$(id -u)" = 0 ]; then SUDO=; else SUDO=sudo; fi
            $SUDO apt-get update -qq
            DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq python3 python3-venv >/dev/null
        fi
        rm -rf "$OPENJD_VENV"
        python3 -m venv "$OPENJD_VENV"
        "$OPENJD_VENV/bin/pip" install -q openjd-cli
    fi
    export PATH="$OPENJD_VENV/bin:$PATH"
fi
