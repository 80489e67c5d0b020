# sim.mk -- the discrete numerical model (core/sim.c, FFTW3 already in PKGS) and its Fig. 6
# bench (bench/fig6.sh plots with gnuplot).
DEBS += gnuplot-nox
CMDS += gnuplot:gnuplot-nox
