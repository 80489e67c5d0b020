# topo.mk -- the topography PSD (core/topo/topo.c, issue 15): FFTW's planner lock lives in
# libfftw3_threads (Debian's libfftw3-dev ships it beside libfftw3; pkg-config's fftw3 does not
# name it).
EXTRA_LIBS += -lfftw3_threads
