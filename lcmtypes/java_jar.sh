#!/bin/sh
# The Java bindings of mvod's LCM types, for lcm-spy (which decodes messages by the classes
# on its classpath) and Java subscribers: lcm-gen --java, javac against LCM's lcm.jar, jar.
# Usage: java_jar.sh LCM_GEN JAVAC JAR LCM_JAR OUT.jar TYPE.lcm...
set -eu
lcm_gen=$1 javac=$2 jar=$3 lcm_jar=$4 out=$5
shift 5
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$lcm_gen" --java --jpath "$tmp/src" "$@"
mkdir "$tmp/classes"
# --release 8: classes any Java from 8 on loads (lcm-spy's JVM may be older than this javac).
"$javac" -nowarn --release 8 -cp "$lcm_jar" -d "$tmp/classes" $(find "$tmp/src" -name '*.java')
"$jar" cf "$out" -C "$tmp/classes" .
