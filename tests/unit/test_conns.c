/* test_conns.c -- the daemon's connection records (server/ljgapd/conns.c) on socket pairs: a
 * connection idle or receiving past receive_s is shut down (its peer reads the end of the
 * stream), a busy one is left alone, going idle restarts the clock, closed records are
 * forgotten, and the per-client request counts enter up to the limit and leave. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <cmocka.h>

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "conns.h"

static void sleep_ms(int ms)
{
    struct timespec t = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&t, NULL);
}

/* 1 when the peer of fd's pair has been shut down (read gives end of stream), 0 when it is
 * still open (no data, would block). */
static int peer_shut(int fd)
{
    char c;
    ssize_t n = recv(fd, &c, 1, MSG_DONTWAIT);
    if (n == 0) return 1;
    assert_true(n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK));
    return 0;
}

static void pair(int sv[2])
{
    assert_int_equal(socketpair(AF_UNIX, SOCK_STREAM, 0, sv), 0);
}

static void test_slow_sender_is_cut(void **state)
{
    conns *cs = conns_start(0.2);
    int idle[2], recv_[2], busy[2];
    conn_rec *a, *b, *c;
    conns_stats st;
    assert_non_null(cs);
    pair(idle);
    pair(recv_);
    pair(busy);
    a = conns_open(cs, idle[0]);
    b = conns_open(cs, recv_[0]);
    c = conns_open(cs, busy[0]);
    assert_non_null(a);
    conns_receiving(cs, b);
    conns_busy(cs, c);
    sleep_ms(100);
    assert_int_equal(peer_shut(idle[1]), 0);
    for (int i = 0; i < 100 && !(peer_shut(idle[1]) && peer_shut(recv_[1])); i++)
        sleep_ms(20);
    assert_int_equal(peer_shut(idle[1]), 1);
    assert_int_equal(peer_shut(recv_[1]), 1);
    assert_int_equal(peer_shut(busy[1]), 0); /* an answer in progress is not cut */
    conns_get_stats(cs, &st);
    assert_int_equal(st.open, 3);
    assert_int_equal(st.cut, 2);
    conns_close(cs, a);
    conns_close(cs, b);
    conns_close(cs, c);
    conns_get_stats(cs, &st);
    assert_int_equal(st.open, 0);
    conns_free(cs);
    for (int i = 0; i < 2; i++) {
        close(idle[i]);
        close(recv_[i]);
        close(busy[i]);
    }
}

/* Each answer restarts the clock: a connection that keeps completing requests is never cut. */
static void test_idle_restarts_clock(void **state)
{
    conns *cs = conns_start(0.3);
    int sv[2];
    conn_rec *a;
    pair(sv);
    a = conns_open(cs, sv[0]);
    for (int i = 0; i < 6; i++) {
        sleep_ms(100);
        conns_receiving(cs, a);
        conns_busy(cs, a);
        conns_idle(cs, a);
    }
    assert_int_equal(peer_shut(sv[1]), 0);
    conns_close(cs, a);
    conns_free(cs);
    close(sv[0]);
    close(sv[1]);
}

static void test_client_counts(void **state)
{
    conns *cs = conns_start(10);
    for (int i = 0; i < 3; i++)
        assert_int_equal(conns_client_enter(cs, "10.0.0.1", 3), 1);
    assert_int_equal(conns_client_enter(cs, "10.0.0.1", 3), 0);
    assert_int_equal(conns_client_enter(cs, "10.0.0.2", 3), 1); /* others are served */
    conns_client_leave(cs, "10.0.0.1");
    assert_int_equal(conns_client_enter(cs, "10.0.0.1", 3), 1);
    assert_int_equal(conns_client_enter(cs, "x", 0), 0);
    conns_client_leave(cs, "never-entered"); /* harmless */
    conns_free(cs);                          /* frees the remaining counts */
}

static void test_null_records(void **state)
{
    conns *cs = conns_start(1);
    conns_receiving(cs, NULL);
    conns_busy(cs, NULL);
    conns_idle(cs, NULL);
    conns_close(cs, NULL);
    conns_free(cs);
    conns_free(NULL);
    assert_null(conns_start(0));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_slow_sender_is_cut),
        cmocka_unit_test(test_idle_restarts_clock),
        cmocka_unit_test(test_client_counts),
        cmocka_unit_test(test_null_records),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
