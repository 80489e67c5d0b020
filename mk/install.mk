# install.mk -- make install / make uninstall (issue 14).
#   make install [PREFIX=/usr/local] [DESTDIR=]
#     $(BINDIR)/ljgap, $(SBINDIR)/ljgapd, $(INCLUDEDIR)/ljgap*.h, $(LIBDIR)/libljgap.a and the
#     shared libljgap.so.VERSION (soname libljgap.so.MAJOR, with the .so.MAJOR and .so links),
#     $(LIBDIR)/pkgconfig/ljgap.pc, $(MANDIR)/man1/ljgap.1 and man8/ljgapd.8, and the systemd
#     unit $(UNITDIR)/ljgapd.service (ExecStart names $(SBINDIR)/ljgapd). Nothing is started.
#   make uninstall [PREFIX=...] [DESTDIR=...]   removes exactly those files
# The library is the numerical core (include/ljgap.h): `pkg-config --cflags --libs ljgap`, or
# with --static for static linking (it then needs GSL and FFTW3). The programs are linked with
# the static libraries, so they need only the system's shared libraries.
PREFIX ?= /usr/local
DESTDIR ?=
BINDIR ?= $(PREFIX)/bin
SBINDIR ?= $(PREFIX)/sbin
LIBDIR ?= $(PREFIX)/lib
INCLUDEDIR ?= $(PREFIX)/include
MANDIR ?= $(PREFIX)/share/man
UNITDIR ?= $(PREFIX)/lib/systemd/system
INSTALL ?= install

INSTALL_HEADERS := $(wildcard include/ljgap*.h)
INSTALL_FILES := $(BINDIR)/ljgap $(SBINDIR)/ljgapd \
                 $(INSTALL_HEADERS:include/%=$(INCLUDEDIR)/%) $(LIBDIR)/libljgap.a \
                 $(LIBDIR)/libljgap.so.$(VERSION) $(LIBDIR)/$(SONAME) $(LIBDIR)/libljgap.so \
                 $(LIBDIR)/pkgconfig/ljgap.pc $(MANDIR)/man1/ljgap.1 $(MANDIR)/man8/ljgapd.8 \
                 $(UNITDIR)/ljgapd.service

# The installed paths put into the pkg-config file and the unit. The unit passes systemd's
# state directory as the job store's --state-dir, when the ljgapd being installed has it (it
# arrives with the persistent job store; an ljgapd without it would refuse to start).
SUBST = sed -e 's|@PREFIX@|$(PREFIX)|g' -e 's|@LIBDIR@|$(LIBDIR)|g' \
            -e 's|@INCLUDEDIR@|$(INCLUDEDIR)|g' -e 's|@SBINDIR@|$(SBINDIR)|g' \
            -e 's|@VERSION@|$(VERSION)|g' -e 's|@EXTRA_LIBS@|$(strip $(EXTRA_LIBS))|g' \
            -e "s|@STATE_DIR_ARGS@|$$($(BUILD)/ljgapd --help | grep -q -- --state-dir && \
                 echo ' --state-dir $${STATE_DIRECTORY}')|g"

.PHONY: install uninstall
install: $(PROGS) $(LIBCORE) $(SHLIB)
	@$(if $(Q),echo "  INSTALL $(DESTDIR)$(PREFIX)")
	$(Q)$(INSTALL) -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(SBINDIR) $(DESTDIR)$(INCLUDEDIR) \
	  $(DESTDIR)$(LIBDIR)/pkgconfig $(DESTDIR)$(MANDIR)/man1 $(DESTDIR)$(MANDIR)/man8 \
	  $(DESTDIR)$(UNITDIR)
	$(Q)$(INSTALL) -m 755 $(BUILD)/ljgap $(DESTDIR)$(BINDIR)/ljgap
	$(Q)$(INSTALL) -m 755 $(BUILD)/ljgapd $(DESTDIR)$(SBINDIR)/ljgapd
	$(Q)$(INSTALL) -m 644 $(INSTALL_HEADERS) $(DESTDIR)$(INCLUDEDIR)/
	$(Q)$(INSTALL) -m 644 $(LIBCORE) $(DESTDIR)$(LIBDIR)/libljgap.a
	$(Q)$(INSTALL) -m 755 $(SHLIB) $(DESTDIR)$(LIBDIR)/libljgap.so.$(VERSION)
	$(Q)ln -sf libljgap.so.$(VERSION) $(DESTDIR)$(LIBDIR)/$(SONAME)
	$(Q)ln -sf $(SONAME) $(DESTDIR)$(LIBDIR)/libljgap.so
	$(Q)$(SUBST) dist/ljgap.pc.in > $(DESTDIR)$(LIBDIR)/pkgconfig/ljgap.pc
	$(Q)$(INSTALL) -m 644 man/ljgap.1 $(DESTDIR)$(MANDIR)/man1/ljgap.1
	$(Q)$(INSTALL) -m 644 man/ljgapd.8 $(DESTDIR)$(MANDIR)/man8/ljgapd.8
	$(Q)$(SUBST) dist/ljgapd.service.in > $(DESTDIR)$(UNITDIR)/ljgapd.service
	$(Q)chmod 644 $(DESTDIR)$(LIBDIR)/pkgconfig/ljgap.pc $(DESTDIR)$(UNITDIR)/ljgapd.service
	@# a real install (no DESTDIR) as root: let the loader find the new shared library
	$(Q)if [ -z "$(DESTDIR)" ] && [ "$$(id -u)" = 0 ] && command -v ldconfig >/dev/null; then \
	  ldconfig; fi

uninstall:
	$(Q)rm -f $(addprefix $(DESTDIR),$(INSTALL_FILES))
	$(Q)if [ -z "$(DESTDIR)" ] && [ "$$(id -u)" = 0 ] && command -v ldconfig >/dev/null; then \
	  ldconfig; fi
