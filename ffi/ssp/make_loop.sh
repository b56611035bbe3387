#!/usr/bin/env bash
# The shipped SSP example: the Fig. 5b stage with friction isolator as the
# plant, its own servo switched off, and the PD servo of pd_controller.c as a
# controller FMU of its own closing the loop, in one SSP 1.0 package.
#
#   bash ffi/ssp/make_loop.sh [OUT_DIR]       (from the repository's root)
#
# Needs a C compiler, the FMI 2.0 headers (FMI_HEADERS, a folder holding
# fmi2Functions.h; FMPy ships them in fmpy/c-code) and `fistage` on the
# PATH or in target/release. Then run it in an importer:
#
#   python ffi/ssp/run_ssp.py OUT_DIR/servo_loop.ssp out.csv --importer fmpy --stop 0.5 --step 1e-4
#   python ffi/ssp/run_ssp.py OUT_DIR/servo_loop.ssp out.csv --importer libcosim --stop 0.5 --step 1e-4
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
out="${1:-out/ssp}"
mkdir -p "$out/controller/binaries/linux64"
if [ -z "${FMI_HEADERS:-}" ]; then
    FMI_HEADERS="$(python3 -c 'import fmpy, os; print(os.path.join(os.path.dirname(fmpy.__file__), "c-code"))')"
fi
cc -std=c99 -Wall -Werror -shared -fPIC -O2 -I "$FMI_HEADERS" "$here/pd_controller.c" \
    -o "$out/controller/binaries/linux64/pd_controller.so"
cp "$here/pd_controller.xml" "$out/controller/modelDescription.xml"
(cd "$out/controller" && rm -f ../pd_controller.fmu &&
    python3 -m zipfile -c ../pd_controller.fmu modelDescription.xml binaries)
fistage="$(command -v fistage || echo target/release/fistage)"
"$fistage" ssp scenarios/paper/fig05b_fi.toml \
    --fmu controller="$out/pd_controller.fmu" \
    --connect "controller.force->plant.servo_force" \
    --connect "plant.encoder.position->controller.position" \
    --connect "plant.encoder.velocity->controller.velocity" \
    --set plant.controller.k=0 --set plant.controller.c=0 \
    --set controller.k=6e4 --set controller.c=100 \
    --stop 0.5 -o "$out/servo_loop.ssp"
