#!/usr/bin/env bash
# Module dependencies point one way: maps <- planner <- preemption <- sim/server; maps <- planner
# <- localizer <- sim/server. The field interfaces are modules of their own below sim and server:
# ntcip (signal controllers over SNMP) behind preemption's SignalController, gnss (receivers via
# gpsd) behind the localizer's fixes.
# A module may include only itself and the modules below it. Usage: layering_test.sh SOURCE_DIR
set -euo pipefail
cd "$1"
declare -A allowed=(
  [maps]="maps"
  [planner]="maps planner"
  [preemption]="maps planner preemption"
  [ntcip]="maps planner preemption ntcip"
  [gnss]="maps planner localizer gnss"
  [sim]="maps planner preemption localizer ntcip gnss sim"
  [server]="maps planner preemption localizer ntcip server"
  [localizer]="maps planner localizer"
  [bench]="maps planner preemption localizer ntcip server bench"
  [web]="web"
)
violations=0
checked=0
for module in "${!allowed[@]}"; do
  [[ -d $module ]] || continue
  while IFS=: read -r file _ include; do
    target=$(sed -E 's/.*#include "([a-z_]+)\/.*/\1/' <<< "$include")
    checked=$((checked + 1))
    if [[ " ${allowed[$module]} " != *" $target "* ]]; then
      echo "layering violation: $file includes $target/ ($module may use: ${allowed[$module]})"
      violations=$((violations + 1))
    fi
  done < <(grep -rnE '#include "[a-z_]+/' "$module" --include='*.hpp' --include='*.cpp' || true)
done
echo "$checked includes checked, $violations violations"
((checked > 0 && violations == 0))
