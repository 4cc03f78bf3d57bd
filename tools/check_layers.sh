#!/usr/bin/env bash
# Checks that the layers include only downwards (README: folders are the data flow). Every target
# gets the project root as include path, so the compiler cannot stop voca/ from including a driver
# by accident; this check does. The rules (a layer must not include the folders listed after it):
#   voca/     -> formats/ drivers/ pipeline/ api/ tools/ platform/   (pure algorithms: no files,
#                                                                   devices, threads, OS)
#   formats/  -> drivers/ pipeline/ api/ tools/   (file readers and writers on top of voca/'s types)
#   drivers/  -> pipeline/ api/ tools/
#   pipeline/ -> api/ tools/
#   platform/ -> drivers/ pipeline/ api/ tools/
#   api/      -> tools/   (the library API, above the pipeline; the command line is its user)
#   api/include/ -> voca/ formats/ drivers/ pipeline/ platform/ api/ tools/   (public headers: only
#                                                              voca_rt/ and the standard library)
#   api/python/  -> voca/ formats/ drivers/ pipeline/ platform/ api/ tools/   (the Python module is a
#                                                              user of the public headers only)
#   examples/ -> voca/ formats/ drivers/ pipeline/ platform/ api/ tools/   (programs a user copies:
#                                                   they build against the installed headers alone)
# Prints every violation as file:line and exits 1 if there is any; 2 on a usage error.
#
#   tools/check_layers.sh [source root]     (default: the repository this script is in)
set -euo pipefail

root=${1:-$(dirname "$0")/..}
if [[ $# -gt 1 || ! -d "$root" ]]; then
  echo "usage: $0 [source root]" >&2
  exit 2
fi
cd "$root"

rules=("voca:formats drivers pipeline api tools platform"
       "formats:drivers pipeline api tools"
       "drivers:pipeline api tools"
       "pipeline:api tools"
       "platform:drivers pipeline api tools"
       "api:tools"
       "api/include:voca formats drivers pipeline platform api tools"
       "api/python:voca formats drivers pipeline platform api tools"
       "examples:voca formats drivers pipeline platform api tools")

violations=0
checked=0
for rule in "${rules[@]}"; do
  layer=${rule%%:*}
  [[ -d "$layer" ]] || continue
  forbidden=${rule#*:}
  pattern="^[[:space:]]*#[[:space:]]*include[[:space:]]*[\"<](${forbidden// /|})/"
  sources=(--include='*.h' --include='*.hpp' --include='*.cpp' --include='*.cc' --include='*.inl')
  checked=$((checked + $(find "$layer" -type f \( -name '*.h' -o -name '*.hpp' -o -name '*.cpp' -o -name '*.cc' \
                                  -o -name '*.inl' \) | wc -l)))
  # One grep per layer: "file:line:text" for every forbidden include.
  while IFS= read -r hit; do
    [[ -n "$hit" ]] || continue
    location=${hit%%:*}
    rest=${hit#*:}
    echo "$location:${rest%%:*}: $layer/ must not include ${forbidden// //, }/: ${rest#*:}"
    violations=$((violations + 1))
  done < <(grep -rnE "${sources[@]}" "$pattern" "$layer" || true)
done

if [[ $checked -eq 0 ]]; then
  echo "$0: no sources found under $(pwd) (expected voca/, formats/, drivers/, pipeline/ or platform/)" >&2
  exit 2
fi
if [[ $violations -gt 0 ]]; then
  echo "$violations include(s) across layers in $checked files" >&2
  exit 1
fi
echo "layers: $checked files, no include across layers"
