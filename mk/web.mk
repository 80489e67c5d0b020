# mk/web.mk -- the page in web/ (issue 5): uPlot from npm, vendored into the served folder, and
# the browser test's tools (playwright-core from npm driving Debian's chromium, never a download).
#
# web/package.json + package-lock.json pin uplot (dependency) and playwright-core (devDependency).
# `npm ci` runs only when web/node_modules is missing or the lock changed (its stamp is npm's own
# hidden lockfile, web/node_modules/.package-lock.json), preferring the local npm cache. The two
# uPlot dist files are copied into web/vendor/ (gitignored), where ljgapd --web web serves them.

CMDS += node:nodejs npm:npm chromium:chromium

WEB_NPM_STAMP := web/node_modules/.package-lock.json
WEB_VENDOR := web/vendor/uPlot.iife.min.js web/vendor/uPlot.min.css

RUN_PREP += $(WEB_VENDOR)
TEST_PREP += $(WEB_VENDOR)

$(WEB_NPM_STAMP): web/package.json web/package-lock.json
	@$(if $(Q),echo "  NPM     web/node_modules")
	$(Q)cd web && npm ci --no-audit --no-fund --prefer-offline --loglevel=error
	$(Q)touch $@

web/vendor/%: $(WEB_NPM_STAMP)
	@mkdir -p $(dir $@)
	@$(if $(Q),echo "  CP      $@")
	$(Q)cp web/node_modules/uplot/dist/$* $@
