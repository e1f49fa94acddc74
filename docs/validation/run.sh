#!/usr/bin/env bash
# Runs the protocol validation of docs/validation.md: each pile of the list, for each seed, once
# with the dynamic protocol and once with the quasi-static one, from the same deposit (a run's
# deposit is a function of its configuration and seed). Usage, from the repository root after a
# build:
#   docs/validation/run.sh OUT_DIR [SEEDS] [PILE ...]
# SEEDS defaults to "1 2 3 4 5 6 7 8 9 10"; PILE to msp-bi6 (the 493-sphere biperiodic pile).
# A run already present (its result.json) is kept, so the script resumes after an interruption.
# QS_FLAGS adds flags to the quasi-static runs only, e.g. QS_FLAGS=--adaptive-dt for a fall on the
# adaptive step (use another OUT_DIR: runs already there are kept whatever their flags).
# COMPARE=preconditioners compares nscd's two preconditioners of MPRGP instead of the protocols:
# each seed once with "sgs" and once with "cholesky", both on the dynamic protocol and the
# adaptive step (the faster way to rest of these piles) with a time limit of 400 t0 (on the
# adaptive step a pile creeps for longer in t0), into OUT_DIR/<pile>/<preconditioner>/.
# PRECONDITIONERS names the two compared (default "sgs cholesky"), e.g. PRECONDITIONERS="sgs switching".
# TOLERANCE sets MPRGP's tolerance of both (default 1e-10), e.g. TOLERANCE=1e-12.
# Then: python3 docs/validation/compare.py OUT_DIR
set -euo pipefail
out=${1:?usage: docs/validation/run.sh OUT_DIR [SEEDS] [PILE ...]}
seeds=${2:-1 2 3 4 5 6 7 8 9 10}
shift $(( $# >= 2 ? 2 : $# ))
piles=("$@")
[[ ${#piles[@]} -gt 0 ]] || piles=(msp-bi6)
confpack=${CONFPACK:-build/apps/confpack}
compare=${COMPARE:-protocols}
case "$compare" in
  protocols) variants=(dynamic quasi-static) ;;
  preconditioners) read -r -a variants <<< "${PRECONDITIONERS:-sgs cholesky}" ;;
  *) echo "COMPARE is protocols or preconditioners, not '$compare'" >&2; exit 2 ;;
esac

flags_of() {
  case "$1" in
    msp-bi6) echo "--length-x 6 --width 6 --periodic-y --height 12 --time-limit 60" ;;  # 493 spheres
    msp-w5)  echo "--length-x 10 --width 5 --height 16 --time-limit 100" ;;              # ~912 spheres
    bsp25-bi6) echo "--length-x 6 --width 6 --periodic-y --height 12 --small-fraction 25 --time-limit 60" ;;
    mpp-bi4) echo "--shape pinacoid --length-x 4 --width 4 --periodic-y --height 8 --time-limit 60" ;;
    *) echo "unknown pile '$1' (msp-bi6, msp-w5, bsp25-bi6, mpp-bi4)" >&2; exit 2 ;;
  esac
}

for pile in "${piles[@]}"; do
  flags=$(flags_of "$pile")
  for seed in $seeds; do
    for variant in "${variants[@]}"; do
      dir="$out/$pile/$variant/s$seed"
      [[ -f "$dir/result.json" ]] && continue
      echo "== $pile $variant seed $seed" >&2
      if [[ $compare == preconditioners ]]; then
        # shellcheck disable=SC2086
        "$confpack" run ${flags% --time-limit *} --time-limit 400 --seed "$seed" --protocol dynamic --adaptive-dt \
          --backend-options "{\"preconditioner\": \"$variant\"${TOLERANCE:+, \"tolerance\": $TOLERANCE}}" \
          --quiet --out "$dir"
        continue
      fi
      protocol=$variant
      # Pinacoids settle dynamically only with damping (README, Known limitations): their
      # dynamic reference is damped, the quasi-static runs are not.
      extra=()
      [[ $pile == mpp-* && $protocol == dynamic ]] && extra=(--backend-options '{"damping": 0.4}')
      # The walled and bidisperse piles creep for hours on the fixed step (msp-w5: about 15 min
      # a run; bsp25-bi6 seed 1 not at rest after 60 t0 and 1,096 s): their dynamic reference
      # takes the adaptive step, the same Moreau-Jean dynamics with longer steps once the grains
      # are slow (README, "Time step").
      [[ ($pile == msp-w5 || $pile == bsp25-*) && $protocol == dynamic ]] && extra=(--adaptive-dt)
      # shellcheck disable=SC2206
      [[ $protocol == quasi-static ]] && extra=(${QS_FLAGS:-})
      # shellcheck disable=SC2086
      "$confpack" run $flags --seed "$seed" --protocol "$protocol" "${extra[@]}" --quiet --out "$dir"
    done
  done
done
