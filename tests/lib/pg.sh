# pg.sh -- a private PostgreSQL cluster for the shell suites and benchmarks (sourced after
# daemon.sh, which gives the scratch directory $tmp). Nothing shared is touched: the cluster
# lives in $tmp/pg, listens on 127.0.0.1 only on a free port, has no Unix socket, and trusts
# loopback connections (it is private and short-lived). When run as root, initdb, pg_ctl and
# postgres run as the user postgres (PostgreSQL refuses root); $tmp is opened to it (0711).
#   pg_init           initdb and a database ljgap; sets PGPORT and PGURL (postgresql://ljgap@...)
#   pg_start          start it (pg_ctl -w); 0 when it accepts connections
#   pg_stop [MODE]    stop it (pg_ctl -m MODE, default fast)
#   pg_cleanup        stop it at once if it runs (for the suite's EXIT trap)
#   pg_sql SQL        psql -At with ON_ERROR_STOP on the database ljgap
# PGBIN is the directory of initdb and pg_ctl (PATH, else the newest /usr/lib/postgresql/*/bin).

PGBIN=$(dirname "$(command -v initdb 2>/dev/null || ls -d /usr/lib/postgresql/*/bin/initdb 2>/dev/null |
    sort -V | tail -n 1)")
PGDIR=$tmp/pg
PGPORT=
PGURL=
PG_AS=()
if [ "$(id -u)" = 0 ]; then
    PG_AS=(runuser -u postgres --)
fi

free_port() { # a TCP port on 127.0.0.1 that nobody listens on now
    python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

pg_init() {
    [ -x "$PGBIN/initdb" ] && [ -x "$PGBIN/pg_ctl" ] || { echo "# no initdb/pg_ctl found" >&2; return 1; }
    mkdir -p "$PGDIR" || return 1
    if [ ${#PG_AS[@]} -gt 0 ]; then
        chmod 0711 "$tmp" && chown postgres "$PGDIR" || return 1
    fi
    "${PG_AS[@]}" "$PGBIN/initdb" -D "$PGDIR/data" -U ljgap -A trust -E UTF8 --locale=C \
        --no-sync >"$PGDIR/initdb.log" 2>&1 || { cat "$PGDIR/initdb.log" >&2; return 1; }
    PGPORT=$(free_port)
    PGURL="postgresql://ljgap@127.0.0.1:$PGPORT/ljgap"
    pg_start || return 1
    "${PG_AS[@]}" psql -q -h 127.0.0.1 -p "$PGPORT" -U ljgap -d postgres -v ON_ERROR_STOP=1 \
        -c 'CREATE DATABASE ljgap' >/dev/null
}

pg_start() {
    "${PG_AS[@]}" "$PGBIN/pg_ctl" -D "$PGDIR/data" -l "$PGDIR/server.log" -w -t 30 \
        -o "-c listen_addresses=127.0.0.1 -p $PGPORT -k '' -c fsync=off -c full_page_writes=off" \
        start >/dev/null 2>&1 || { tail -n 5 "$PGDIR/server.log" >&2; return 1; }
}

pg_stop() {
    "${PG_AS[@]}" "$PGBIN/pg_ctl" -D "$PGDIR/data" -m "${1:-fast}" -w -t 30 stop >/dev/null 2>&1
}

pg_cleanup() {
    local pid
    [ -f "$PGDIR/data/postmaster.pid" ] || return 0
    pid=$(head -n 1 "$PGDIR/data/postmaster.pid")
    pg_stop immediate || { [ -n "$pid" ] && kill -QUIT "$pid" 2>/dev/null; }
}

pg_sql() {
    psql -q -At -v ON_ERROR_STOP=1 "$PGURL" -c "$1"
}
