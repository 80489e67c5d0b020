# mk/contract.mk -- the contract test's tools (issue 20): ajv, ajv-formats, swagger-parser and
# the OpenAPI-to-JSON-Schema converter from npm, pinned in tests/contract/package.json and
# package-lock.json, installed by `npm ci` for make test only (never for make run or building).
# `npm ci` runs again only when the lock changed (its stamp is npm's own hidden lockfile).

CONTRACT_NPM_STAMP := tests/contract/node_modules/.package-lock.json
TEST_PREP += $(CONTRACT_NPM_STAMP)

$(CONTRACT_NPM_STAMP): tests/contract/package.json tests/contract/package-lock.json
	@$(if $(Q),echo "  NPM     tests/contract/node_modules (ajv, swagger-parser)")
	$(Q)cd tests/contract && npm ci --no-audit --no-fund --prefer-offline --loglevel=error
	$(Q)touch $@
