/* gt_guard.h: the runtime's network guard: one source per socket for the session, strangers
 * counted by address, sequence numbers checked against a plausible window with a rule to
 * resynchronise. Part of gtmodel's robot runtime (gtmodel.codegen.robot_runtime); no heap.
 *
 * A source (the robot, the tracker) is either named on the command line (--robot, --tracker:
 * an IPv4 address, optionally with its port) or taken from the first valid datagram; once
 * locked it is one address and one port for the rest of the session. Any other sender is a
 * stranger: never parsed, never answered, counted by address (the first GT_GUARD_MAX_STRANGERS
 * addresses, the rest in one count).
 *
 * The sequence rule (IPOC, EGM seqno, the tracker's seq): with d = seq - last (modulo the
 * field's width, signed), 0 < d <= window is accepted; -window <= d <= 0 is a duplicate or an
 * older packet (held); any other d is out of the window (held) and a candidate: when resync_n
 * consecutive candidates are each within the window of the one before (a restarted robot's new
 * sequence), the last of them is accepted and the sequence restarts from it. A packet accepted
 * in the window clears the candidates, so a forged number among the robot's own packets is held
 * once and changes nothing.
 */
#ifndef GT_GUARD_H
#define GT_GUARD_H

#include <netinet/in.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/socket.h>
#include <sys/types.h>

#define GT_GUARD_MAX_STRANGERS 16

typedef struct gt_source {
    int named;                /* 1: an address was named (--robot / --tracker) */
    int named_port;           /* 1: with its port */
    int locked;               /* 1: the session's source is fixed */
    struct sockaddr_in addr;  /* the named address, then the locked source */
} gt_source;

/* "A.B.C.D" or "A.B.C.D:PORT" (port 1..65535). Returns 0, or -1 for another form. */
int gt_source_parse(const char *text, gt_source *s);
/* 1 when a datagram from `from` is the source's: the locked source, or before the lock any sender
 * matching what was named (anyone when nothing was named); 0: a stranger. */
int gt_source_match(const gt_source *s, const struct sockaddr_in *from);
/* Lock the source to `from` (address and port). */
void gt_source_lock(gt_source *s, const struct sockaddr_in *from);
/* "A.B.C.D:PORT" of an address into out[cap]. */
void gt_address_text(const struct sockaddr_in *a, char *out, size_t cap);

typedef struct gt_stranger {
    uint32_t ip;      /* network order */
    uint16_t port;    /* network order */
    int socket;       /* 0 the robot's socket, 1 the sensor's */
    uint64_t count;
} gt_stranger;

typedef struct gt_strangers {
    gt_stranger e[GT_GUARD_MAX_STRANGERS];
    int n;
    uint64_t total, other; /* all datagrams of strangers; those from addresses beyond the table */
} gt_strangers;

/* Count one datagram of a stranger on socket (0 robot, 1 sensor). */
void gt_strangers_count(gt_strangers *t, const struct sockaddr_in *from, int socket);

#define GT_SEQ_ACCEPT 0 /* newer, within the window */
#define GT_SEQ_OLD 1    /* a duplicate or older, within the window */
#define GT_SEQ_OUT 2    /* beyond the window: held; a candidate for resynchronisation */
#define GT_SEQ_RESYNC 3 /* the resync_n-th consistent candidate: accepted, the sequence restarts from it */

typedef struct gt_seqwin {
    int have, cand_n;
    uint64_t last, cand;
    uint64_t out_of_window, resyncs;
} gt_seqwin;

/* Check seq (bits: 32 or 64, the field's width) against the window; updates *w. */
int gt_seq_check(gt_seqwin *w, uint64_t seq, int bits, uint64_t window, int resync_n);

/* one datagram without blocking (recvfrom's result, MSG_TRUNC: the datagram's length); *dropped raised to the
 * kernel's running count of datagrams it dropped on this socket for a full receive queue (SO_RXQ_OVFL, set on the socket) */
ssize_t gt_recv(int fd, void *data, size_t size, struct sockaddr_in *from, socklen_t *fromlen, uint64_t *dropped);

#endif
