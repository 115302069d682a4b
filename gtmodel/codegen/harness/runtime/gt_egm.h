/* gt_egm.h: ABB EGM over UDP: the robot's EgmRobot decoded and the EgmSensor (or
 * EgmSensorPathCorr) reply encoded, through nanopb (nanopb/, egm.pb.c generated from ABB's
 * egm.proto with egm.options: static allocation only). Part of gtmodel's robot runtime.
 */
#ifndef GT_EGM_H
#define GT_EGM_H

#include <stddef.h>
#include <stdint.h>

/* Longest datagram accepted [bytes] (a longer one: GT_EGM_TOO_LONG). */
#define GT_EGM_MAX_LEN 4096
/* Joints per EgmJoints (egm.options: max_count 12; more is a decode error). */
#define GT_EGM_MAX_JOINTS 12

/* The measured fields of EgmRobot, in this order (gtmodel.codegen.robot_runtime.EGM_INPUTS):
 * feedback.joints.0..11 0-11, feedback.cartesian.x|y|z 12-14, feedback.orient.u0..u3 15-18,
 * planned.joints.0..11 19-30, planned.cartesian.x|y|z 31-33, planned.orient.u0..u3 34-37,
 * feedback.externalJoints.0..5 38-43, planned.externalJoints.0..5 44-49. */
#define GT_EGM_NFIELDS 50

/* The modes of the reply. */
#define GT_EGM_JOINT 0           /* EgmSensor, planned.joints (deg; linear axes mm) */
#define GT_EGM_CARTESIAN 1       /* EgmSensor, planned.cartesian.pos (mm), orientation echoed */
#define GT_EGM_PATH_CORRECTION 2 /* EgmSensorPathCorr, pathCorr.pos (mm) and age (ms) */

#define GT_EGM_OK 0
#define GT_EGM_MALFORMED 1  /* not an EgmRobot with header.seqno */
#define GT_EGM_TOO_LONG 2
#define GT_EGM_NON_FINITE 3 /* decoded, with its seqno, but a position is NaN or infinite */

typedef struct gt_egm_robot {
    double field[GT_EGM_NFIELDS];
    uint64_t present; /* bit i: field i was in the message */
    uint32_t seqno;
    int has_tm;
    uint32_t tm;      /* header.tm [ms] */
    int has_orient;   /* the orientation echoed in a Cartesian reply: planned's, else feedback's */
    double orient[4];
} gt_egm_robot;

/* Decode one datagram. Returns a GT_EGM_* code; *out is written in every case. */
int gt_egm_parse(const unsigned char *buf, size_t len, gt_egm_robot *out);

/* Encode the reply of mode into out[cap]: header (seqno echoed, tm, mtype CORRECTION or
 * PATH_CORRECTION) and n values (joint: n joints; Cartesian and path correction: x, y, z);
 * orient (4 values) may be NULL; age_ms for a path correction. Returns the length or -1. */
int gt_egm_compose(unsigned char *out, size_t cap, int mode, uint32_t seqno, uint32_t tm, const double *value, int n,
                   const double *orient, uint32_t age_ms);

#endif
