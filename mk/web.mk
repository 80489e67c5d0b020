# mk/web.mk -- the page in web/ (issue 5): uPlot from npm, vendored into the served folder, and
# the browser test's tools (playwright-core from npm driving Debian's chromium, never a download).
#
# web/package.json + package-lock.json pin uplot (dependency) and playwright-core (devDependency).
# `npm ci` runs only when web/node_modules is missing or the lock changed (its stamp is npm's own
# hidden lockfile, web/node_modules/.package-lock.json), preferring the local npm cache; building
# installs the dependency alone (--omit=dev), make test the devDependency too. The two uPlot
# dist files are copied into web/vendor/ (gitignored), from where the Makefile compiles them into
# ljgapd with the rest of the page (ljgapd --web web serves them from there too). So building
# ljgapd needs npm (uPlot is on npm only); the browser test adds chromium and playwright-core.

CMDS += node:nodejs npm:npm
TEST_CMDS += chromium:chromium

WEB_NPM_STAMP := web/node_modules/.package-lock.json
WEB_VENDOR := web/vendor/uPlot.iife.min.js web/vendor/uPlot.min.css

WEB_PLAYWRIGHT := web/node_modules/playwright-core/package.json
TEST_PREP += $(WEB_PLAYWRIGHT)

$(WEB_NPM_STAMP): web/package.json web/package-lock.json
	@$(if $(Q),echo "  NPM     web/node_modules (uplot)")
	$(Q)cd web && npm ci --omit=dev --no-audit --no-fund --prefer-offline --loglevel=error
	$(Q)touch $@

$(WEB_PLAYWRIGHT): web/package.json web/package-lock.json
	@$(if $(Q),echo "  NPM     web/node_modules (playwright-core)")
	$(Q)cd web && npm ci --no-audit --no-fund --prefer-offline --loglevel=error
	$(Q)touch $@ $(WEB_NPM_STAMP)

web/vendor/%: $(WEB_NPM_STAMP)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CP      $@")
	$(Q)cp web/node_modules/uplot/dist/$* $@
