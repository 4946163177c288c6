#!/bin/sh
# Makes sure what the tests and the bench need is installed: Embree 3
# (libembree-dev, the comparison), embree-tools (the furBall_A model),
# clang (libFuzzer) and libstb-dev (stb_image_write.h, the render example).
# As root it installs them with apt-get; otherwise it says what to run.
# gnuplot-nox (the bench's chart) is optional and installed when possible.
set -e
missing=""
[ -f /usr/include/embree3/rtcore.h ] || missing="$missing libembree-dev"
[ -f /usr/share/doc/embree3/models/furBall_A.bin.gz ] || missing="$missing embree-tools"
command -v clang >/dev/null 2>&1 || missing="$missing clang"   # the libFuzzer targets
[ -f /usr/include/stb/stb_image_write.h ] || missing="$missing libstb-dev"   # examples/render.c
command -v gnuplot >/dev/null 2>&1 || optional="gnuplot-nox"
[ -n "$missing$optional" ] || exit 0
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "installing:$missing $optional" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >&2
    apt-get install -y -qq $missing >&2
    [ -z "$optional" ] || apt-get install -y -qq $optional >&2 || echo "gnuplot-nox not installed: the bench will print tables without the chart" >&2
    exit 0
fi
if [ -n "$missing" ]; then
    echo "missing:$missing. Run: sudo apt-get install$missing" >&2
    exit 1
fi
