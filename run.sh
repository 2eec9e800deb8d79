#!/usr/bin/env bash
# One-step set-up for isoforce on Debian (root or sudo), then:
#   bash run.sh app    install and launch the desktop app (on Xvfb when there is no display)
#   bash run.sh test   install, lint (ruff, import-linter) and run the whole test suite (GUI tests under Xvfb)
# Anything after the first word goes to the app (isoforce ...) or to pytest.
set -euo pipefail
cd "$(dirname "$0")"

# Debian packages Qt's xcb plugin and the virtual X server need (see DESIGN.md, Tests).
DEBS=(xvfb xauth libxcb-icccm4 libxcb-image0 libxcb-keysyms1 libxcb-randr0 libxcb-render-util0
      libxcb-shape0 libxcb-xinerama0 libxcb-xkb1 libxkbcommon-x11-0 libxcb-cursor0)

install_debs() {
    local missing=()
    for pkg in "${DEBS[@]}"; do
        dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
    done
    [ ${#missing[@]} -eq 0 ] && return 0
    echo "run.sh: installing Debian packages: ${missing[*]}"
    local sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

install_python() {
    # A virtual environment that can see the machine's numpy/scipy/pytest, so only what is
    # missing is downloaded. The package is installed editable with its test extra.
    if [ ! -x .venv/bin/python ]; then
        python3 -m venv --system-site-packages .venv
    fi
    .venv/bin/python -m pip install -q --disable-pip-version-check -e ".[test,bench]"
    # Where PYTHONDONTWRITEBYTECODE is set (many container images set it) pip writes no
    # bytecode, and every isoforce process then compiles its ~600 library modules from source
    # as it imports them (about 0.5 s of a 2 s 'isoforce figure'). Compiled once here; files
    # already compiled are skipped. A file that does not compile (PySide6's code templates) is
    # only left to be read from source.
    local purelib
    purelib="$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_path("purelib"))')"
    .venv/bin/python -m compileall -q -j 0 -x '\.tmpl\.py$' "$purelib" app kinematics metrics resources >/dev/null \
        || echo "run.sh: some modules were not compiled to bytecode (they are read from source)"
    # The compiled map kernels (metrics.kernels, numba): compiling them took 10-36 s on this 2-core
    # machine under load (isoforce bench: compile.cold_seconds), loading them from numba's cache
    # 0.8-2 s with numba's import (compile.seconds). Compiled here, once, so that the first map
    # after an install does not pay the compile; later runs find the cache and skip it.
    .venv/bin/python -c "from metrics import runtime; runtime.warm()" \
        || echo "run.sh: the compiled kernels were not cached (the first map compiles them)"
}

cmd="${1:-}"
[ $# -gt 0 ] && shift
case "$cmd" in
    app)
        install_debs
        install_python
        if [ -z "${DISPLAY:-}" ] && [ -z "${WAYLAND_DISPLAY:-}" ]; then
            echo "run.sh: no display; launching on a virtual X screen (xvfb-run). Use 'isoforce figure' for headless figures."
            exec xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/isoforce "$@"
        fi
        exec .venv/bin/isoforce "$@"
        ;;
    test)
        install_debs
        install_python
        # pytest-xvfb starts a virtual X server for the session; the Qt offscreen platform
        # cannot host the VTK render window, so it must not be forced here.
        unset QT_QPA_PLATFORM
        # The house habits, checked by tools: lint and import order (ruff), and the layer
        # contracts of pyproject.toml (import-linter). Either failing fails the run.
        .venv/bin/ruff check .
        .venv/bin/lint-imports
        # Test files spread over the cores (pytest-xdist, at most 4 processes: each holds a Qt app,
        # an X server and the kernels); a file's tests stay in one process, with its fixtures.
        # Add -n 0 after the command for one process.
        workers="$(nproc 2>/dev/null || echo 1)"
        [ "$workers" -gt 4 ] && workers=4
        exec .venv/bin/python -m pytest -n "$workers" --dist loadfile "$@"
        ;;
    *)
        echo "usage: bash run.sh app [isoforce args] | bash run.sh test [pytest args]" >&2
        exit 2
        ;;
esac
