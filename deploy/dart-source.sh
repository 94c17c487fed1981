#!/usr/bin/env bash
# Fetches Debian's source of the installed DART (the package libdart-dev was built from,
# the same version and Debian's patches) into .deps/dart/<version>/, for the build to
# compile it again without assertions (cmake/DartWithoutAssertions.cmake).
#
# Why: Debian builds DART with CMAKE_BUILD_TYPE=None, which leaves NDEBUG undefined, so
# every Eigen index check and DART assert runs inside the physics step. The same source
# built as DART's Release type builds it (-O3 -DNDEBUG) gives the same numbers, bit for bit
# (a test checks the state digest), about a third faster (docs/benchmarks.md, "Physics server").
#
# The download goes through apt (`apt-get source`), so the files are checked against
# Debian's signed index, with a private list of deb-src entries made from this machine's
# own apt sources: the machine's apt configuration is not changed. Idempotent: with the
# source in place it does nothing and needs no network. Without network or without a
# source for this version it says so and exits 0: the physics then runs on Debian's build.
# A failure is remembered (.deps/dart/<version>.unavailable) so that every `make` does not
# try again; delete that file, or set SKILLBUS_DART_SOURCE_RETRY=1, to try again.
set -euo pipefail
cd "$(dirname "$0")/.."

ver=$(dpkg-query -W -f='${source:Version}' libdart-dev 2>/dev/null || true)
if [ -z "$ver" ]; then
  echo "dart-source: libdart-dev is not installed; nothing to fetch" >&2
  exit 0
fi
dest=.deps/dart/${ver//:/_}  # (an epoch's colon would split the build's RUNPATH)
if [ -f "$dest/CMakeLists.txt" ]; then exit 0; fi
unavailable=$dest.unavailable
if [ -f "$unavailable" ] && [ "${SKILLBUS_DART_SOURCE_RETRY:-0}" != 1 ]; then
  echo "dart-source: no source of DART $ver ($(head -1 "$unavailable")); the physics runs on Debian's build." \
       "Delete $unavailable to try again" >&2
  exit 0
fi
mkdir -p .deps/dart
# give_up WHAT LOG: says why, remembers it, and leaves the build to Debian's DART.
give_up() {
  echo "dart-source: $1 (the physics runs on Debian's DART build):" >&2
  tail -5 "$2" >&2
  echo "$1, $(date -u +%Y-%m-%dT%H:%MZ)" > "$unavailable"
  exit 0
}

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/lists/partial" "$work/cache/archives/partial" "$work/parts" "$work/get"
: > "$work/sources.list"
# The machine's own apt sources as deb-src entries (one-line .list files and deb822
# .sources files), in a list only this script reads.
for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list; do
  [ -f "$f" ] && sed -n 's/^[[:space:]]*deb[[:space:]]/deb-src /p' "$f" >> "$work/sources.list"
done
for f in /etc/apt/sources.list.d/*.sources; do
  [ -f "$f" ] && sed 's/^Types:.*/Types: deb-src/' "$f" > "$work/parts/$(basename "$f")"
done
apt_opts=(-o "Dir::Etc::SourceList=$work/sources.list" -o "Dir::Etc::SourceParts=$work/parts"
          -o "Dir::State::Lists=$work/lists" -o "Dir::Cache=$work/cache" -o "APT::Sandbox::User=$(id -un)"
          -o "Debug::NoLocking=1")

echo "dart-source: fetching Debian's source of DART $ver (for a build without assertions)"
# (A repository of the machine's without sources makes `update` complain; what matters is
# whether Debian's index then has the source, which `apt-get source` says.)
apt-get "${apt_opts[@]}" -qq update > "$work/update.log" 2>&1 || true
if ! (cd "$work/get" && apt-get "${apt_opts[@]}" -qq --only-source source --download-only "dart=$ver") \
     > "$work/source.log" 2>&1; then
  cat "$work/update.log" >> "$work/source.log"
  give_up "apt-get source dart=$ver failed" "$work/source.log"
fi
# dpkg-source checks the tarballs against the .dsc's checksums and applies Debian's patches.
rm -rf "$dest.partial"
if ! dpkg-source --no-copy -x "$work/get/dart_${ver#*:}.dsc" "$dest.partial" > "$work/extract.log" 2>&1; then
  rm -rf "$dest.partial"
  give_up "unpacking the source failed" "$work/extract.log"
fi
mv "$dest.partial" "$dest"
rm -f "$unavailable"
echo "dart-source: $dest"
