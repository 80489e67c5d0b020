# sim.mk -- the discrete numerical model (core/sim/sim.c, FFTW3 already in PKGS) and its Fig. 6
# bench (bench/fig6.sh plots with gnuplot: mk/bench.mk installs it for make bench).
