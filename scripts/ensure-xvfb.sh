# Sourced by ./run-tests: the viewer's tests (tests/reyes_view.rs) open real windows on an Xvfb
# server and send keys and mouse drags with xdotool; both are installed from Debian's packages
# when missing. The tests fail loudly without them, never skip.
if ! command -v Xvfb >/dev/null || ! command -v xdotool >/dev/null; then
    echo "Xvfb or xdotool missing: installing xvfb and xdotool (for tests/reyes_view.rs)" >&2
    if [ "$(id -u)" = 0 ]; then SUDO=; else SUDO=sudo; fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq xvfb xdotool >/dev/null
fi
