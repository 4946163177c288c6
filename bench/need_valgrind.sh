#!/bin/sh
# need_valgrind.sh WHO: installs valgrind where it is missing (Debian, as
# root), as make test installs its tools; otherwise says what to run and
# fails. WHO names the caller in the message (make profile, make instructions).
command -v valgrind > /dev/null 2>&1 && exit 0
if [ "$(id -u)" = 0 ] && command -v apt-get > /dev/null 2>&1; then
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq valgrind >&2
else
    echo "$1: valgrind is missing. Run: sudo apt-get install valgrind" >&2
    exit 1
fi
