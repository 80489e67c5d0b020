# nginx.sh -- nginx with deploy/nginx/ljgap.conf in front of ljgapd instances, for the shell
# suites and benchmarks (sourced after daemon.sh and pg.sh, which give $tmp and free_port).
# Everything lives in $tmp/nginx (its -p prefix: configuration, logs, pid, temporary files);
# it listens on 127.0.0.1 only, on a free port, with one worker process (so its round robin
# over the instances is strict). As root, its worker runs as nobody, as nginx does by default.
#   nginx_conf PORT...   write $tmp/nginx/nginx.conf: the deploy file with its upstream servers
#                        replaced by 127.0.0.1:PORT for each PORT, and listening on NGINX_PORT
#                        (picked here once); sets NGINX_URL; fails if the file changed shape
#   nginx_start          start it in the foreground process NGINX_PID (daemon off; under
#                        $NGINX_WRAP, such as nice, if set); waits for it
#   nginx_stop           stop it (SIGQUIT: graceful; SIGKILL after 5 s) and wait
# The upstream lines of the deploy file are "server 127.0.0.1:8081 ..." and "... :8082 ...".

NGINX_DIR=$tmp/nginx
NGINX_PORT=
NGINX_URL=
NGINX_PID=

nginx_conf() {
    local servers="" p
    mkdir -p "$NGINX_DIR" || return 1
    [ -n "$NGINX_PORT" ] || NGINX_PORT=$(free_port)
    NGINX_URL=http://127.0.0.1:$NGINX_PORT
    for p in "$@"; do servers="$servers    server 127.0.0.1:$p max_fails=2 fail_timeout=5s;\\n"; done
    # the deploy file: its listen line and its two example servers replaced
    sed -e "s|^\( *\)listen 80;|\1listen 127.0.0.1:$NGINX_PORT;|" \
        -e "/^ *server 127\.0\.0\.1:8082 /d" \
        -e "s|^ *server 127\.0\.0\.1:8081 .*|$servers|" \
        deploy/nginx/ljgap.conf >"$NGINX_DIR/ljgap.conf" || return 1
    if ! grep -q "listen 127.0.0.1:$NGINX_PORT;" "$NGINX_DIR/ljgap.conf" ||
        [ "$(grep -c '^ *server 127\.0\.0\.1:' "$NGINX_DIR/ljgap.conf")" != $# ]; then
        echo "# deploy/nginx/ljgap.conf no longer has 'listen 80;' and the two example servers" >&2
        return 1
    fi
    local user=""
    [ "$(id -u)" = 0 ] && user="user nobody nogroup;" && chmod 0711 "$tmp" && chmod 0755 "$NGINX_DIR"
    cat >"$NGINX_DIR/nginx.conf" <<EOF
$user
worker_processes 1;
daemon off;
pid $NGINX_DIR/nginx.pid;
error_log $NGINX_DIR/error.log warn;
events { worker_connections 1024; }
http {
    access_log $NGINX_DIR/access.log;
    client_body_temp_path $NGINX_DIR/body;
    proxy_temp_path $NGINX_DIR/proxy;
    fastcgi_temp_path $NGINX_DIR/fastcgi;
    uwsgi_temp_path $NGINX_DIR/uwsgi;
    scgi_temp_path $NGINX_DIR/scgi;
    include $NGINX_DIR/ljgap.conf;
}
EOF
}

nginx_check() { # nginx -t on the configuration
    nginx -t -q -p "$NGINX_DIR" -e "$NGINX_DIR/error.log" -c "$NGINX_DIR/nginx.conf" 2>&1
}

nginx_start() {
    ${NGINX_WRAP:-} nginx -p "$NGINX_DIR" -e "$NGINX_DIR/error.log" -c "$NGINX_DIR/nginx.conf" \
        2>>"$NGINX_DIR/error.log" &
    NGINX_PID=$!
    for _ in $(seq 1 100); do
        curl -s -o /dev/null --max-time 1 "$NGINX_URL/healthz" && return 0
        kill -0 "$NGINX_PID" 2>/dev/null || break
        sleep 0.05
    done
    tail -n 5 "$NGINX_DIR/error.log" >&2
    return 1
}

nginx_stop() {
    [ -n "$NGINX_PID" ] || return 0
    kill -QUIT "$NGINX_PID" 2>/dev/null
    for _ in $(seq 1 100); do
        kill -0 "$NGINX_PID" 2>/dev/null || break
        sleep 0.05
    done
    kill -KILL "$NGINX_PID" 2>/dev/null
    wait "$NGINX_PID" 2>/dev/null
    NGINX_PID=
}
