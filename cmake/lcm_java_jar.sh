#!/bin/sh
# lcm_java_jar.sh LCM_GEN JAVAC JAR LCM_JAR WORKDIR OUT_JAR file.lcm...
# Generates Java classes for the LCM types and packs them into OUT_JAR (for lcm-spy).
set -e
lcm_gen=$1 javac=$2 jar=$3 lcm_jar=$4 work=$5 out=$6
shift 6
rm -rf "$work"
mkdir -p "$work/src" "$work/classes" "$(dirname "$out")"
"$lcm_gen" --java --jpath "$work/src" "$@"
find "$work/src" -name '*.java' > "$work/sources.txt"
"$javac" -nowarn --release 8 -cp "$lcm_jar" -d "$work/classes" @"$work/sources.txt" 2>/dev/null ||
  "$javac" -nowarn -cp "$lcm_jar" -d "$work/classes" @"$work/sources.txt"
"$jar" cf "$out" -C "$work/classes" .
