#!/usr/bin/env bash
# Install.IntoAPrefixAndRunFromAnotherFolder: `cmake --install` into a temporary prefix, then the
# installed programs run from an unrelated folder and find their installed data (default world,
# robot, parameter files, groups, the bridge's page): simulate, run, --print-config, a launcher listing.
set -euo pipefail
build=$1
prefix=$(mktemp -d)
work=$(mktemp -d)
trap 'rm -rf "$prefix" "$work"' EXIT
cmake --install "$build" --prefix "$prefix" >/dev/null
cd "$work"
contains() { [[ "$1" == *"$2"* ]] || { echo "expected '$2' in: $1" >&2; exit 1; }; }
contains "$("$prefix/bin/polarslam" --version)" "polarslam "
contains "$("$prefix/bin/polarslam" simulate --seconds 20 -o sim.lcmlog)" "$prefix/share/polarslam/config/worlds/office.yaml"
"$prefix/bin/polarslam" run --log sim.lcmlog --pipeline ekf --config "$prefix/share/polarslam/config/ekf.yaml" --out ekf >/dev/null
test -s ekf/report.json && test -s ekf/trajectory.tum && test -s ekf/map.pgm
contains "$("$prefix/bin/polarslam" run --pipeline psm-slam --print-config)" "keyframe_angle_deg"
contains "$("$prefix/bin/polarslam-launch" "$prefix/share/polarslam/config/groups/replay.yaml" --list)" polarslam-psm-slam
# The bridge's page is installed with it and found from the installed program.
test -s "$prefix/share/polarslam/web/index.html" && test -s "$prefix/share/polarslam/web/app.js"
contains "$("$prefix/bin/polarslam-bridge" --help)" "$prefix/share/polarslam/web"
test -s "$prefix/share/polarslam/java/polarslam_lcmtypes.jar"
test -x "$prefix/bin/polarslam-lcm-spy"
echo "installed into $prefix; ran from $work"
