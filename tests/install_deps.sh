#!/bin/sh
# Makes sure what the tests and the bench need is installed: Embree 3
# (libembree-dev, the comparison), embree-tools (the furBall_A model),
# clang (libFuzzer), libstb-dev (stb_image_write.h, the render example),
# mingw-w64 and wine (the Windows tier: tests/run_windows.sh), and the
# AArch64 cross compilers and qemu (the AArch64 tier: tests/run_arm64.sh).
# As root it installs them with apt-get; otherwise it says what to run.
# gnuplot-nox (the bench's chart) is optional and installed when possible.
set -e
missing=""; cross=""; optional=""
[ -f /usr/include/embree3/rtcore.h ] || missing="$missing libembree-dev"
[ -f /usr/share/doc/embree3/models/furBall_A.bin.gz ] || missing="$missing embree-tools"
command -v clang >/dev/null 2>&1 || missing="$missing clang"   # the libFuzzer targets
[ -f /usr/include/stb/stb_image_write.h ] || missing="$missing libstb-dev"   # examples/render.c
# the cross tiers: installed as root; elsewhere they skip, saying so
command -v x86_64-w64-mingw32-gcc >/dev/null 2>&1 || cross="$cross gcc-mingw-w64-x86-64"
command -v x86_64-w64-mingw32-g++ >/dev/null 2>&1 || cross="$cross g++-mingw-w64-x86-64"   # its compile matrix (C++11)
command -v wine >/dev/null 2>&1 || cross="$cross wine64"
# the AArch64 tier (tests/run_arm64.sh) and its compile matrix
command -v aarch64-linux-gnu-gcc >/dev/null 2>&1 || cross="$cross gcc-aarch64-linux-gnu libc6-dev-arm64-cross"
command -v aarch64-linux-gnu-g++ >/dev/null 2>&1 || cross="$cross g++-aarch64-linux-gnu"
command -v qemu-aarch64 >/dev/null 2>&1 || cross="$cross qemu-user"
command -v gnuplot >/dev/null 2>&1 || optional="gnuplot-nox"
[ -n "$missing$cross$optional" ] || exit 0
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "installing:$missing$cross $optional" >&2
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >&2
    [ -z "$missing$cross" ] || apt-get install -y -qq $missing $cross >&2
    [ -z "$optional" ] || apt-get install -y -qq $optional >&2 || echo "gnuplot-nox not installed: the bench will print tables without the chart" >&2
    exit 0
fi
if [ -n "$missing" ]; then
    echo "missing:$missing. Run: sudo apt-get install$missing" >&2
    exit 1
fi
[ -z "$cross" ] || echo "the Windows or AArch64 tier will be skipped:$cross missing. Run: sudo apt-get install$cross" >&2
