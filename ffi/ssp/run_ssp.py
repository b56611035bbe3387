"""Runs an SSP 1.0 system in a co-simulation importer at a fixed
communication step and writes the chosen connectors' values as CSV.

    python run_ssp.py servo_loop.ssp out.csv --importer fmpy --stop 0.5 --step 1e-4
    python run_ssp.py servo_loop.ssp out.csv --importer libcosim --stop 0.5 --step 1e-4

Importers: `fmpy` (FMPy's SSP master, https://github.com/CATIA-Systems/FMPy)
and `libcosim` (the Open Simulation Platform's libcosim through libcosimpy).
Both exchange connector values once per communication step (an input is
the output of the step before, held), so the result converges to a
monolithic run at first order in the step.

FMPy's master reads the system's parameter bindings but applies only the
parameter set it is given: this script gives it the bindings of each
component, by their hierarchical names (`controller.k`). libcosim applies
them itself.

Each CSV row holds the time at the end of a step and the outputs there
(`--outputs plant.encoder.position,controller.force`).
"""

import argparse
import csv
import sys


def run_fmpy(args, outputs):
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import read_ssd

    class Parameter:
        def __init__(self, name, value):
            self.name = name
            self.value = value

    class ParameterSet:
        def __init__(self, parameters):
            self.parameters = parameters

    system = read_ssd(args.ssp).system
    parameters = []
    for element in system.elements:
        for binding in element.parameterBindings:
            for values in binding.parameterValues:
                for p in values.parameters:
                    parameters.append(Parameter(element.name + "." + p.name, p.value))
    result = simulate_ssp(
        args.ssp,
        stop_time=args.stop,
        step_size=args.step,
        parameter_set=ParameterSet(parameters),
    )
    rows = []
    for row in result:
        # A row holds the connectors after the step from its time.
        rows.append([float(row["time"]) + args.step] + [float(row[name]) for name in outputs])
    return rows


def run_libcosim(args, outputs):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    # libcosim logs every FMI call at its default level.
    log_output_level(CosimLogLevel.WARNING)

    step_ns = int(round(args.step * 1e9))
    execution = CosimExecution.from_ssp_file(args.ssp, step_size=step_ns)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    references = []
    for name in outputs:
        component, variable = name.split(".", 1)
        index = execution.slave_index_from_instance_name(component)
        found = [v for v in execution.slave_variables(index) if v.name.decode() == variable]
        if not found:
            raise SystemExit("libcosim: %s has no variable %s" % (component, variable))
        references.append((index, found[0].reference))
    steps = int(round(args.stop / args.step))
    rows = []
    for k in range(steps):
        execution.step(1)
        values = [observer.last_real_values(index, [vr])[0] for index, vr in references]
        rows.append([(k + 1) * args.step] + values)
    execution.stop()
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("ssp")
    parser.add_argument("csv")
    parser.add_argument("--importer", choices=["fmpy", "libcosim"], required=True)
    parser.add_argument("--stop", type=float, required=True)
    parser.add_argument("--step", type=float, required=True)
    parser.add_argument("--outputs", default="plant.encoder.position")
    args = parser.parse_args()
    outputs = args.outputs.split(",")
    run = {"fmpy": run_fmpy, "libcosim": run_libcosim}[args.importer]
    rows = run(args, outputs)
    with open(args.csv, "w", newline="") as out:
        writer = csv.writer(out)
        writer.writerow(["time"] + outputs)
        for row in rows:
            writer.writerow([repr(float(v)) for v in row])


if __name__ == "__main__":
    sys.exit(main())
