"""Many instances of one FMU at once: co-simulation instances of one stage
FMU (64 by default), each with its own value of a parameter, stepped on
parallel threads with FMPy, and each checked bit for bit against the same
instance run alone.

    python python/examples/fmu_parallel_instances.py STAGE.fmu \
        [--instances 64] [--threads 8] [--parameter controller.c] \
        [--low 50] [--high 400] [--stop 0.5] [--step 1e-3] [--json]

Make the FMU with ``fistage fmu scenarios/paper/fig05b_fi.toml -o stage.fmu``
(or ``fistage.load(...).export_fmu(...)``); FMPy is the only requirement.

What the FMU guarantees: its instances are independent (each holds its own
model, state and FMU states; the library shares only the set of live
instances, behind a lock held for the membership check alone), so different
instances may be called from different threads at the same time; one
instance must be called from one thread at a time (as FMI requires). FMPy
calls the library through ctypes, which releases Python's lock during each
call, so the threads run on every core.
"""

import argparse
import concurrent.futures
import hashlib
import json
import shutil
import time

import fmpy
from fmpy.fmi2 import FMU2Slave
from fmpy.model_description import read_model_description


def run_instance(description, folder, index, reference, value, outputs, stop, step):
    """One instance from start to stop with `reference` set to `value`: the
    outputs at the end (as exact hex floats) and a digest of every step's."""
    slave = FMU2Slave(
        guid=description.guid,
        unzipDirectory=folder,
        modelIdentifier=description.coSimulation.modelIdentifier,
        instanceName="stage%d" % index,
    )
    slave.instantiate(loggingOn=False)
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([reference], [value])
    slave.exitInitializationMode()
    digest = hashlib.sha256()
    steps = int(round(stop / step))
    values = []
    for k in range(steps):
        slave.doStep(currentCommunicationPoint=k * step, communicationStepSize=step)
        values = slave.getReal(outputs)
        digest.update(" ".join(float(v).hex() for v in values).encode())
    slave.terminate()
    slave.freeInstance()
    return {"final": [float(v).hex() for v in values], "digest": digest.hexdigest()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("fmu")
    parser.add_argument("--instances", type=int, default=64)
    parser.add_argument("--threads", type=int, default=8)
    parser.add_argument("--parameter", default="controller.c")
    parser.add_argument("--low", type=float, default=50.0)
    parser.add_argument("--high", type=float, default=400.0)
    parser.add_argument("--stop", type=float, default=0.5)
    parser.add_argument("--step", type=float, default=1e-3)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()

    description = read_model_description(args.fmu, validate=True)
    by_name = {v.name: v for v in description.modelVariables}
    if args.parameter not in by_name:
        raise SystemExit("%s: no variable %s" % (args.fmu, args.parameter))
    reference = by_name[args.parameter].valueReference
    outputs = [v.valueReference for v in description.modelVariables if v.causality == "output"]
    n = args.instances
    values = [args.low + (args.high - args.low) * i / max(n - 1, 1) for i in range(n)]
    folder = fmpy.extract(args.fmu)
    try:
        job = lambda i: run_instance(description, folder, i, reference, values[i], outputs,
                                     args.stop, args.step)
        start = time.perf_counter()
        serial = [job(i) for i in range(n)]
        serial_seconds = time.perf_counter() - start
        start = time.perf_counter()
        with concurrent.futures.ThreadPoolExecutor(max_workers=args.threads) as pool:
            parallel = list(pool.map(job, range(n)))
        parallel_seconds = time.perf_counter() - start
    finally:
        shutil.rmtree(folder, ignore_errors=True)

    differing = [i for i in range(n) if serial[i] != parallel[i]]
    distinct = len({s["digest"] for s in serial})
    report = {
        "instances": n,
        "threads": args.threads,
        "parameter": args.parameter,
        "values": values,
        "differing": differing,
        "distinct_trajectories": distinct,
        "serial_seconds": serial_seconds,
        "parallel_seconds": parallel_seconds,
        "serial": serial,
        "parallel": parallel,
    }
    if args.json:
        print(json.dumps(report))
        return
    print("%d instances of %s, %s from %g to %g, %d distinct trajectories"
          % (n, args.fmu, args.parameter, args.low, args.high, distinct))
    print("serial %.2f s, %d threads %.2f s" % (serial_seconds, args.threads, parallel_seconds))
    if differing:
        raise SystemExit("instances %s differ between their parallel and serial runs" % differing)
    print("every parallel run equals its serial run bit for bit")


if __name__ == "__main__":
    main()
