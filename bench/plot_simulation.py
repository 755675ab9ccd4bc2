#!/usr/bin/env python3
"""Plots of issue 18 from bench/nonlinear_tones' CSV files (and bench/simulation_compare.py's,
when present), drawn by gnuplot into docs/simulation/*.svg and *.png.

    python3 bench/plot_simulation.py RESULTS_DIR IMAGES_DIR

- tone_slopes: |Z/(A G) - 1| against the amplitude A, log-log, one line per model and frequency
  (the difference between the nonlinear steady state and the frequency response);
- middle_ear_spl: the stapes velocity against the sound pressure level at 0.5, 1 and 4 kHz, the
  simulated fundamental beside the linear prediction, and below it their ratio in dB;
- work_precision (from simulation_compare.csv): error against run time, ours and SciPy's.
"""
import csv
import os
import subprocess
import sys


def gnuplot(images, work, name, body, size=(760, 520)):
    script = os.path.join(work, name + ".gp")
    with open(script, "w") as f:
        for term, ext, extra in (("svg", "svg", " dynamic background rgb 'white'"), ("pngcairo", "png", "")):
            f.write("set terminal %s size %d,%d font 'sans,11'%s\n" % (term, size[0], size[1], extra))
            f.write("set output '%s'\n" % os.path.join(images, name + "." + ext))
            f.write(body + "\nunset output\nreset\n")
    subprocess.run(["gnuplot", script], check=True, cwd=work)


def read(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def tone_slopes(results, images, work):
    if not os.path.exists(os.path.join(results, "tone_slopes.csv")):
        return
    rows = read(os.path.join(results, "tone_slopes.csv"))
    groups = {}
    for r in rows:
        groups.setdefault((r["model"], r["hz"]), []).append((float(r["amplitude"]), float(r["relative_error"])))
    plots = []
    for i, ((model, hz), points) in enumerate(sorted(groups.items())):
        data = os.path.join(work, "slope_%d.dat" % i)
        with open(data, "w") as f:
            for a, e in sorted(points):
                f.write("%.6g %.6g\n" % (a / max(p[0] for p in points), max(e, 1e-16)))
        plots.append("'%s' using 1:2 with linespoints lw 2 pt 7 ps 0.6 title '%s, %s Hz'" % (data, model.replace("_", " "), hz))
    body = """set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set grid
set key top left
set xlabel 'amplitude A / largest amplitude (rotor 1000 N, chain 3 N, middle ear 20 kPa)'
set ylabel '|Z / (A G) - 1|'
set title 'Nonlinear steady state against the frequency response (slopes 1 and 2 dashed)'
plot """ + ", ".join(plots) + ", 1e-5*x dt 2 lc rgb 'gray' title 'slope 1', 1e-2*x**2 dt 3 lc rgb 'gray' title 'slope 2'"
    gnuplot(images, work, "tone_slopes", body)


def middle_ear_spl(results, images, work):
    if not os.path.exists(os.path.join(results, "middle_ear_spl.csv")):
        return
    rows = read(os.path.join(results, "middle_ear_spl.csv"))
    by_hz = {}
    for r in rows:
        by_hz.setdefault(r["hz"], []).append(r)
    colours = {"500": "#1f4e9c", "1000": "#b03030", "4000": "#2a8a3a"}
    top, bottom = [], []
    for hz, rs in sorted(by_hz.items(), key=lambda kv: float(kv[0])):
        data = os.path.join(work, "spl_%s.dat" % hz)
        with open(data, "w") as f:
            for r in rs:
                f.write("%s %s %s %.6g\n" % (r["spl_db"], r["v_linear"], r["v_simulated"], max(abs(float(r["ratio_db"])), 1e-12)))
        c = colours.get(hz, "black")
        top.append("'%s' using 1:2 with lines dt 2 lw 1.5 lc rgb '%s' title '%s Hz linear'" % (data, c, hz))
        top.append("'%s' using 1:3 with linespoints pt 7 ps 0.5 lw 2 lc rgb '%s' title '%s Hz simulated'" % (data, c, hz))
        bottom.append("'%s' using 1:4 with linespoints pt 7 ps 0.5 lw 2 lc rgb '%s' title '%s Hz'" % (data, c, hz))
    body = """set multiplot layout 2,1 title 'Middle ear: stapes velocity against the sound pressure level (geometric nonlinearity only)'
set grid
set logscale y
set format y '10^{%L}'
set key top left
set xrange [60:220]
set ylabel '|v\\_stapes| (fundamental) [m/s]'
plot """ + ", ".join(top) + """
set ylabel '|20 log_{10}(v_{sim} / v_{lin})| [dB]'
set xlabel 'sound pressure level [dB SPL re 20 µPa]'
set arrow from 60,1 to 220,1 nohead dt 2 lc rgb 'black'
set label '1 dB' at 202,3
set arrow from 120,graph 0 to 120,graph 1 nohead dt 2 lw 1.5 lc rgb '#888888'
set label 'measured onset in temporal bones: about 120 dB' at 122,1e-3
plot """ + ", ".join(bottom) + "\nunset multiplot"
    gnuplot(images, work, "middle_ear_spl", body, size=(760, 720))


def work_precision(results, images, work):
    path = os.path.join(results, "simulation_compare.csv")
    if not os.path.exists(path):
        return
    rows = read(path)
    problems = sorted({r["problem"] for r in rows})
    for p in problems:
        plots = []
        for i, solver in enumerate(sorted({r["solver"] for r in rows if r["problem"] == p})):
            data = os.path.join(work, "wp_%s_%d.dat" % (p, i))
            with open(data, "w") as f:
                for r in rows:
                    if r["problem"] == p and r["solver"] == solver and r["error"] not in ("", "nan"):
                        f.write("%s %s\n" % (r["seconds"], max(float(r["error"]), 1e-16)))
            plots.append("'%s' using 1:2 with linespoints lw 2 pt 7 ps 0.6 title '%s'" % (data, solver))
        body = """set logscale xy
set format x '10^{%L}'
set format y '10^{%L}'
set grid
set key top right
set xlabel 'run time [s] (median)'
set ylabel 'relative error against the reference run, max|y - y_ref| / max|y_ref|' noenhanced
set title 'Work and precision: """ + p.replace("_", " ") + """'
plot """ + ", ".join(plots)
        gnuplot(images, work, "work_precision_" + p, body)


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: plot_simulation.py RESULTS_DIR IMAGES_DIR")
    results, images = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    work = os.path.join(results, "plots_simulation")
    os.makedirs(work, exist_ok=True)
    os.makedirs(images, exist_ok=True)
    tone_slopes(results, images, work)
    middle_ear_spl(results, images, work)
    work_precision(results, images, work)


if __name__ == "__main__":
    main()
