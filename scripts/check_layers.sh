#!/usr/bin/env bash
# The layering rule of docs/architecture.md: a file in src/LAYER/ includes only its own layer and the
# layers below it. Layers of the same rank (render and protocol, server and client, apps and web) are siblings and
# never include each other. Prints every include that goes up or sideways and exits 1 if there is one.
set -euo pipefail
cd "$(dirname "$0")/.."

declare -A rank=(
  [common]=0 [io]=1 [spm]=2
  [builder]=3 [dag]=3 [multilevel]=3
  [render]=4 [protocol]=4
  [server]=5 [client]=5
  [apps]=6 [web]=6
  [bench]=7
)

violations=0
checked=0
for dir in src/*/; do
  layer=$(basename "$dir")
  if [[ -z "${rank[$layer]+set}" ]]; then
    echo "check_layers: src/$layer is not a known layer (add it to scripts/check_layers.sh and docs/architecture.md)" >&2
    violations=$((violations + 1))
    continue
  fi
  while IFS= read -r -d '' file; do
    checked=$((checked + 1))
    while IFS=: read -r line include; do
      target=${include%%/*}
      [[ "$include" == */* ]] || continue  # a sibling file of the same directory
      if [[ -z "${rank[$target]+set}" ]]; then
        echo "$file:$line: includes \"$include\" from no known layer"
        violations=$((violations + 1))
      elif [[ "$target" != "$layer" && ${rank[$target]} -ge ${rank[$layer]} ]]; then
        direction=up
        [[ ${rank[$target]} -eq ${rank[$layer]} ]] && direction=sideways
        echo "$file:$line: $layer includes \"$include\" ($direction: $target)"
        violations=$((violations + 1))
      fi
    done < <(grep -n -o -E '^[[:space:]]*#[[:space:]]*include[[:space:]]*"[^"]+"' "$file" |
             sed -E 's/^([0-9]+):.*"([^"]+)"/\1:\2/')
  done < <(find "$dir" -type f \( -name '*.h' -o -name '*.cpp' \) -print0)
done

if [[ $violations -gt 0 ]]; then
  echo "check_layers: $violations include(s) break the layering (docs/architecture.md, \"Layers\")" >&2
  exit 1
fi
echo "check_layers: $checked files, every include goes down"
