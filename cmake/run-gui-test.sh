#!/usr/bin/env bash
# Runs a GUI test with a real OpenGL context: the current display if there is
# one, otherwise a private Xvfb server. Mesa's llvmpipe renders in software.
set -eu
export LIBGL_ALWAYS_SOFTWARE=1
export QT_QUICK_BACKEND=${QT_QUICK_BACKEND:-}
if [ -n "${DISPLAY:-}" ] && xdpyinfo >/dev/null 2>&1; then
  exec "$@"
fi
exec xvfb-run -a -s "-screen 0 1280x1024x24" "$@"
