/* statedir.h -- temporary state directories for the job store tests (include after cmocka.h):
 * make one, remove it with everything in it, and change its database behind the store's back
 * (as an operator with the sqlite3 shell, or a damaged disk, would). */
#ifndef LJGAP_TEST_STATEDIR_H
#define LJGAP_TEST_STATEDIR_H

#include "check.h"

#include <sqlite3.h>

#include <ftw.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define STATEDIR_LEN 256 /* room for a test's directory names */

/* A fresh directory /tmp/ljgap-test-XXXXXX (mode 0711: another user may pass through it, as
 * the permission tests need) into root (STATEDIR_LEN bytes). */
static void statedir_make(char *root)
{
    snprintf(root, STATEDIR_LEN, "/tmp/ljgap-test-XXXXXX");
    assert_non_null(mkdtemp(root));
    assert_int_equal(chmod(root, 0711), 0);
}

static int statedir_rm1(const char *path, const struct stat *sb, int flag, struct FTW *ftw)
{
    (void)sb;
    (void)ftw;
    chmod(path, 0700); /* a directory a test made read-only */
    return flag == FTW_DP ? rmdir(path) : unlink(path);
}

/* rm -rf root */
static void statedir_remove(const char *root)
{
    nftw(root, statedir_rm1, 16, FTW_DEPTH | FTW_PHYS);
}

/* Runs sql on dir/jobs.sqlite through a connection of its own (checks off, so rows the
 * schema forbids can be written too); fails the test if SQLite refuses. */
static void statedir_sql(const char *dir, const char *sql)
{
    char path[PATH_MAX], *msg = NULL;
    sqlite3 *db = NULL;
    snprintf(path, sizeof path, "%s/jobs.sqlite", dir);
    assert_int_equal(sqlite3_open_v2(path, &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, NULL),
                     SQLITE_OK);
    sqlite3_busy_timeout(db, 5000);
    if (sqlite3_exec(db, "PRAGMA ignore_check_constraints = ON;", NULL, NULL, &msg) != SQLITE_OK ||
        sqlite3_exec(db, sql, NULL, NULL, &msg) != SQLITE_OK) {
        print_error("%s: %s\n", sql, msg ? msg : "?");
        sqlite3_free(msg);
        sqlite3_close(db);
        fail();
    }
    sqlite3_close(db);
}

#endif
