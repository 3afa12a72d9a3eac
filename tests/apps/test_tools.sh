#!/usr/bin/env bash
# The Python tools on a results file holding every field: render.py lists them and colours by
# one of each kind, refuses unknown fields and components with one line, compare_runs.py pairs
# steps at one load in order, plot_series.py plots.
# Usage: test_tools.sh PATH/TO/depthfem SOURCE_DIR
source "$(dirname "$0")/preamble.sh"
py=/usr/bin/python3
is_png() { [ "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ]; }

"$exe" run "$src/apps/scenes/bars_drop.json" --out "$tmp/bars.h5" --set dynamic.duration=0.25 \
  --set 'output={"stress": true, "strain": true}' > /dev/null 2>&1 || fail "bars_drop run exited $?"
"$py" "$src/apps/tools/render.py" "$tmp/bars.h5" --list > "$tmp/list.txt" || fail "--list exited $?"
for field in displacement velocity depth stress von_mises strain volume_ratio contact_pressure \
    contact_traction contact_gap contact_fraction body; do
  grep -q "^$field " "$tmp/list.txt" || fail "--list misses $field: $(cat "$tmp/list.txt")"
done
# One field of each kind: node vector (magnitude, component), tet tensor component, tet scalar,
# triangle scalar and vector component, body names.
for color in displacement velocity:z stress:xy volume_ratio contact_pressure contact_traction:z \
    body; do
  "$py" "$src/apps/tools/render.py" "$tmp/bars.h5" "$tmp/$color.png" --color "$color" --step 40 \
    --reference 2> "$tmp/err.txt" || fail "render --color $color: $(cat "$tmp/err.txt")"
  is_png "$tmp/$color.png" || fail "render --color $color wrote no PNG"
done

"$py" "$src/apps/tools/render.py" "$tmp/bars.h5" "$tmp/x.png" --color stress 2> "$tmp/err.txt"
[ $? -eq 1 ] || fail "a tensor without a component must exit 1"
[ "$(wc -l < "$tmp/err.txt")" -eq 1 ] || fail "expected one error line: $(cat "$tmp/err.txt")"
grep -q "stress is a symmetric tensor: choose a component (stress:xx|yy|zz|xy|yz|xz)" "$tmp/err.txt" \
  || fail "tensor message: $(cat "$tmp/err.txt")"
"$py" "$src/apps/tools/render.py" "$tmp/bars.h5" "$tmp/x.png" --color pressure 2> "$tmp/err.txt"
[ $? -eq 1 ] || fail "an unknown field must exit 1"
grep -q "bars.h5: step 49: no field 'pressure' in this step (fields: displacement, velocity," \
  "$tmp/err.txt" || fail "unknown field message: $(cat "$tmp/err.txt")"
"$py" "$src/apps/tools/render.py" "$tmp/bars.h5" "$tmp/x.png" --step 99 2> "$tmp/err.txt"
grep -q "bars.h5: no step 99 (steps 0 to 49)" "$tmp/err.txt" || fail "step message: $(cat "$tmp/err.txt")"

# compare_runs.py pairs the steps at one load in order: ball_drop's settle steps all hold the
# full load, and a run against itself differs by nothing at any of them.
"$exe" run "$src/apps/scenes/ball_drop.json" --out "$tmp/ball.h5" > /dev/null 2>&1 \
  || fail "ball_drop run exited $?"
"$py" "$src/apps/tools/compare_runs.py" "$tmp/ball.h5" "$tmp/ball.h5" --tolerance 0 > "$tmp/cmp.txt" \
  || fail "compare_runs of a run against itself: $(tail -2 "$tmp/cmp.txt")"
[ "$(grep -c "^load 1 " "$tmp/cmp.txt")" -gt 1 ] || fail "ball_drop has no settle steps: $(cat "$tmp/cmp.txt")"

"$py" "$src/apps/tools/plot_series.py" "$tmp/bars.h5" "$tmp/series.png" || fail "plot_series exited $?"
is_png "$tmp/series.png" || fail "plot_series wrote no PNG"
echo "tools: all checks passed"
