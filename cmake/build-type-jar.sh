#!/bin/sh
# build-type-jar.sh LCM_GEN JAVAC JAR LCM_JAR OUT_JAR WORK_DIR LCM_FILES...
# Generates Java classes of our LCM types and packs them into a jar for lcm-spy.
set -e
lcm_gen=$1; javac=$2; jar=$3; lcm_jar=$4; out=$5; work=$6; shift 6
rm -rf "$work"; mkdir -p "$work/src" "$work/classes"
"$lcm_gen" --java --jpath "$work/src" "$@"
"$javac" -nowarn -source 8 -target 8 -cp "$lcm_jar" -d "$work/classes" "$work"/src/polarslam/*.java 2>"$work/javac.log" \
  || { cat "$work/javac.log" >&2; exit 1; }
"$jar" cf "$out" -C "$work/classes" .
