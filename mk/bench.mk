# bench.mk -- the error-against-time and stability benchmarks (bench/errtime.sh) plot with
# gnuplot (PNG through the cairo terminal of gnuplot-nox).
DEBS += gnuplot-nox
CMDS += gnuplot:gnuplot-nox
