#!/bin/sh
# Regenerates the .vdb test grids (a few KB each). Needs Debian's OpenVDB 10:
#   apt-get install g++ libopenvdb-dev libboost-dev libtbb-dev libimath-dev
set -e
cd "$(dirname "$0")"
g++ -O1 -std=c++17 make_vdb.cpp -o /tmp/make_vdb -lopenvdb -ltbb -lImath-3_1
/tmp/make_vdb
