/* gt_guard.c: one source per socket, strangers counted, the sequence window (see gt_guard.h). */
#define _GNU_SOURCE /* SO_RXQ_OVFL, CMSG_* */
#include "gt_guard.h"

#include <arpa/inet.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int gt_source_parse(const char *text, gt_source *s)
{
    char host[32];
    const char *colon;
    size_t len;
    memset(s, 0, sizeof *s);
    if (text == NULL) return -1;
    colon = strchr(text, ':');
    len = colon ? (size_t)(colon - text) : strlen(text);
    if (len == 0 || len >= sizeof host) return -1;
    memcpy(host, text, len);
    host[len] = '\0';
    s->addr.sin_family = AF_INET;
    if (inet_pton(AF_INET, host, &s->addr.sin_addr) != 1) return -1;
    if (colon) {
        char *end = NULL;
        long port;
        if (colon[1] < '0' || colon[1] > '9') return -1;
        port = strtol(colon + 1, &end, 10);
        if (*end != '\0' || port < 1 || port > 65535) return -1;
        s->addr.sin_port = htons((uint16_t)port);
        s->named_port = 1;
    }
    s->named = 1;
    return 0;
}

int gt_source_match(const gt_source *s, const struct sockaddr_in *from)
{
    if (from->sin_family != AF_INET) return 0;
    if (s->locked || s->named_port)
        return from->sin_addr.s_addr == s->addr.sin_addr.s_addr && from->sin_port == s->addr.sin_port;
    if (s->named) return from->sin_addr.s_addr == s->addr.sin_addr.s_addr;
    return 1;
}

void gt_source_lock(gt_source *s, const struct sockaddr_in *from)
{
    s->addr.sin_family = AF_INET;
    s->addr.sin_addr = from->sin_addr;
    s->addr.sin_port = from->sin_port;
    s->locked = 1;
}

void gt_address_text(const struct sockaddr_in *a, char *out, size_t cap)
{
    char ip[INET_ADDRSTRLEN] = "?";
    inet_ntop(AF_INET, &a->sin_addr, ip, sizeof ip);
    snprintf(out, cap, "%s:%u", ip, (unsigned)ntohs(a->sin_port));
}

void gt_strangers_count(gt_strangers *t, const struct sockaddr_in *from, int socket)
{
    int i;
    ++t->total;
    for (i = 0; i < t->n; ++i) {
        gt_stranger *e = &t->e[i];
        if (e->ip == from->sin_addr.s_addr && e->port == from->sin_port && e->socket == socket) {
            ++e->count;
            return;
        }
    }
    if (t->n < GT_GUARD_MAX_STRANGERS) {
        gt_stranger *e = &t->e[t->n++];
        e->ip = from->sin_addr.s_addr;
        e->port = from->sin_port;
        e->socket = socket;
        e->count = 1;
        return;
    }
    ++t->other;
}

/* seq - ref as a signed number of the field's width */
static int64_t gt_seq_diff(uint64_t seq, uint64_t ref, int bits)
{
    if (bits == 32) return (int64_t)(int32_t)((uint32_t)seq - (uint32_t)ref);
    return (int64_t)(seq - ref);
}

static int gt_within(int64_t d, uint64_t window)
{
    return d > 0 && (uint64_t)d <= window;
}

int gt_seq_check(gt_seqwin *w, uint64_t seq, int bits, uint64_t window, int resync_n)
{
    int64_t d;
    if (!w->have) {
        w->have = 1;
        w->last = seq;
        w->cand_n = 0;
        return GT_SEQ_ACCEPT;
    }
    d = gt_seq_diff(seq, w->last, bits);
    if (gt_within(d, window)) {
        w->last = seq;
        w->cand_n = 0;
        return GT_SEQ_ACCEPT;
    }
    if (d <= 0 && (d == INT64_MIN ? 0 : (uint64_t)(-d) <= window)) return GT_SEQ_OLD;
    ++w->out_of_window;
    if (w->cand_n > 0 && gt_within(gt_seq_diff(seq, w->cand, bits), window)) ++w->cand_n;
    else w->cand_n = 1;
    w->cand = seq;
    if (w->cand_n >= resync_n) {
        w->last = seq;
        w->cand_n = 0;
        ++w->resyncs;
        return GT_SEQ_RESYNC;
    }
    return GT_SEQ_OUT;
}

/* one datagram without blocking (recvfrom's result), and the kernel's running count of the datagrams it
 * dropped on this socket for a full receive queue (SO_RXQ_OVFL, carried by the datagram) into *dropped */
ssize_t gt_recv(int fd, void *data, size_t size, struct sockaddr_in *from, socklen_t *fromlen, uint64_t *dropped)
{
    union { char buf[CMSG_SPACE(sizeof(uint32_t))]; struct cmsghdr align; } control;
    struct iovec iov;
    struct msghdr msg;
    struct cmsghdr *c;
    ssize_t n;
    iov.iov_base = data;
    iov.iov_len = size;
    memset(&msg, 0, sizeof msg);
    msg.msg_name = from;
    msg.msg_namelen = *fromlen;
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control.buf;
    msg.msg_controllen = sizeof control.buf;
    n = recvmsg(fd, &msg, MSG_DONTWAIT | MSG_TRUNC);
    if (n < 0) return n;
    *fromlen = msg.msg_namelen;
    for (c = CMSG_FIRSTHDR(&msg); c != NULL; c = CMSG_NXTHDR(&msg, c))
        if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL && c->cmsg_len >= CMSG_LEN(sizeof(uint32_t))) {
            uint32_t count;
            memcpy(&count, CMSG_DATA(c), sizeof count);
            if (count > *dropped) *dropped = count;
        }
    return n;
}
