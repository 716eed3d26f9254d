#!/bin/sh
# Builds the CGAL peer (benchmarks only; Debian: apt-get install -y libcgal-dev libgmp-dev
# libmpfr-dev). Header-only CGAL: one compile of a few minutes. Prints the binary's path.
set -e
here=$(cd "$(dirname "$0")" && pwd)
out="$here/build/cgal_minkowski"
if [ ! -d /usr/include/CGAL ]; then
    echo "CGAL headers not found (/usr/include/CGAL): apt-get install -y libcgal-dev" >&2
    exit 3
fi
mkdir -p "$here/build"
if [ ! -x "$out" ] || [ "$here/cgal_minkowski.cpp" -nt "$out" ]; then
    ${CXX:-g++} -O2 -DNDEBUG -std=c++17 "$here/cgal_minkowski.cpp" -o "$out" -lgmp -lmpfr
fi
echo "$out"
