# bench.mk -- the error-against-time and stability benchmarks (bench/errtime.sh) plot with
# gnuplot (PNG through the cairo terminal of gnuplot-nox); bench/run.sh counts instructions with
# valgrind's callgrind; bench/jobstore.sh and bench/topo.sh read the daemon's answers with jq.
BENCH_DEBS += gnuplot-nox
BENCH_CMDS += gnuplot:gnuplot-nox valgrind:valgrind jq:jq
