/* gt_egm.c: EgmRobot decode and EgmSensor / EgmSensorPathCorr encode through nanopb (see gt_egm.h).
 * The message structs are static (one per direction: the runtime's cycle is one thread), so the
 * ~2 kB EgmRobot is not on the real-time thread's stack. */
#include "gt_egm.h"

#include <math.h>
#include <string.h>

#include "egm.pb.h"
#include "pb_decode.h"
#include "pb_encode.h"

static abb_egm_EgmRobot gt_egm_rx;
static abb_egm_EgmSensor gt_egm_tx;
static abb_egm_EgmSensorPathCorr gt_egm_tx_pc;

static void gt_egm_put(gt_egm_robot *out, int f, double v, int *non_finite)
{
    out->field[f] = v;
    out->present |= (uint64_t)1 << f;
    if (!isfinite(v)) *non_finite = 1;
}

static void gt_egm_joints(gt_egm_robot *out, int first, int cap, const abb_egm_EgmJoints *j, int *non_finite)
{
    int i;
    for (i = 0; i < (int)j->joints_count && i < cap; ++i) gt_egm_put(out, first + i, j->joints[i], non_finite);
    for (; i < (int)j->joints_count; ++i) { /* beyond the fields: still checked */
        if (!isfinite(j->joints[i])) *non_finite = 1;
    }
}

static void gt_egm_pose(gt_egm_robot *out, int first, const abb_egm_EgmPose *p, int *non_finite)
{
    if (p->has_pos) {
        gt_egm_put(out, first, p->pos.x, non_finite);
        gt_egm_put(out, first + 1, p->pos.y, non_finite);
        gt_egm_put(out, first + 2, p->pos.z, non_finite);
    }
    if (p->has_orient) {
        gt_egm_put(out, first + 3, p->orient.u0, non_finite);
        gt_egm_put(out, first + 4, p->orient.u1, non_finite);
        gt_egm_put(out, first + 5, p->orient.u2, non_finite);
        gt_egm_put(out, first + 6, p->orient.u3, non_finite);
    }
    if (p->has_euler && !(isfinite(p->euler.x) && isfinite(p->euler.y) && isfinite(p->euler.z))) *non_finite = 1;
}

int gt_egm_parse(const unsigned char *buf, size_t len, gt_egm_robot *out)
{
    pb_istream_t in;
    int non_finite = 0;
    abb_egm_EgmRobot *r = &gt_egm_rx;
    memset(out, 0, sizeof *out);
    if (buf == NULL) return GT_EGM_MALFORMED;
    if (len > GT_EGM_MAX_LEN) return GT_EGM_TOO_LONG;
    memset(r, 0, sizeof *r);
    in = pb_istream_from_buffer(buf, len);
    if (!pb_decode(&in, abb_egm_EgmRobot_fields, r)) return GT_EGM_MALFORMED;
    if (!r->has_header || !r->header.has_seqno) return GT_EGM_MALFORMED;
    out->seqno = r->header.seqno;
    out->has_tm = r->header.has_tm;
    out->tm = r->header.tm;
    if (r->has_feedBack) {
        if (r->feedBack.has_joints) gt_egm_joints(out, 0, 12, &r->feedBack.joints, &non_finite);
        if (r->feedBack.has_cartesian) gt_egm_pose(out, 12, &r->feedBack.cartesian, &non_finite);
        if (r->feedBack.has_externalJoints) gt_egm_joints(out, 38, 6, &r->feedBack.externalJoints, &non_finite);
    }
    if (r->has_planned) {
        if (r->planned.has_joints) gt_egm_joints(out, 19, 12, &r->planned.joints, &non_finite);
        if (r->planned.has_cartesian) gt_egm_pose(out, 31, &r->planned.cartesian, &non_finite);
        if (r->planned.has_externalJoints) gt_egm_joints(out, 44, 6, &r->planned.externalJoints, &non_finite);
    }
    if (r->has_utilizationRate && !isfinite(r->utilizationRate)) non_finite = 1;
    if (r->has_planned && r->planned.has_cartesian && r->planned.cartesian.has_orient) {
        out->has_orient = 1;
        memcpy(out->orient, &out->field[34], sizeof out->orient);
    } else if (r->has_feedBack && r->feedBack.has_cartesian && r->feedBack.cartesian.has_orient) {
        out->has_orient = 1;
        memcpy(out->orient, &out->field[15], sizeof out->orient);
    }
    return non_finite ? GT_EGM_NON_FINITE : GT_EGM_OK;
}

int gt_egm_compose(unsigned char *out, size_t cap, int mode, uint32_t seqno, uint32_t tm, const double *value, int n,
                   const double *orient, uint32_t age_ms)
{
    pb_ostream_t os;
    int i;
    if (out == NULL || value == NULL) return -1;
    for (i = 0; i < n; ++i) {
        if (!isfinite(value[i])) return -1;
    }
    os = pb_ostream_from_buffer(out, cap);
    if (mode == GT_EGM_PATH_CORRECTION) {
        abb_egm_EgmSensorPathCorr *m = &gt_egm_tx_pc;
        if (n != 3) return -1;
        memset(m, 0, sizeof *m);
        m->has_header = true;
        m->header.has_seqno = true;
        m->header.seqno = seqno;
        m->header.has_tm = true;
        m->header.tm = tm;
        m->header.has_mtype = true;
        m->header.mtype = abb_egm_EgmHeader_MessageType_MSGTYPE_PATH_CORRECTION;
        m->has_pathCorr = true;
        m->pathCorr.pos.x = value[0];
        m->pathCorr.pos.y = value[1];
        m->pathCorr.pos.z = value[2];
        m->pathCorr.age = age_ms;
        if (!pb_encode(&os, abb_egm_EgmSensorPathCorr_fields, m)) return -1;
    } else {
        abb_egm_EgmSensor *m = &gt_egm_tx;
        memset(m, 0, sizeof *m);
        m->has_header = true;
        m->header.has_seqno = true;
        m->header.seqno = seqno;
        m->header.has_tm = true;
        m->header.tm = tm;
        m->header.has_mtype = true;
        m->header.mtype = abb_egm_EgmHeader_MessageType_MSGTYPE_CORRECTION;
        m->has_planned = true;
        if (mode == GT_EGM_JOINT) {
            if (n < 1 || n > GT_EGM_MAX_JOINTS) return -1;
            m->planned.has_joints = true;
            m->planned.joints.joints_count = (pb_size_t)n;
            for (i = 0; i < n; ++i) m->planned.joints.joints[i] = value[i];
        } else if (mode == GT_EGM_CARTESIAN) {
            if (n != 3) return -1;
            m->planned.has_cartesian = true;
            m->planned.cartesian.has_pos = true;
            m->planned.cartesian.pos.x = value[0];
            m->planned.cartesian.pos.y = value[1];
            m->planned.cartesian.pos.z = value[2];
            if (orient != NULL) {
                for (i = 0; i < 4; ++i) {
                    if (!isfinite(orient[i])) return -1;
                }
                m->planned.cartesian.has_orient = true;
                m->planned.cartesian.orient.u0 = orient[0];
                m->planned.cartesian.orient.u1 = orient[1];
                m->planned.cartesian.orient.u2 = orient[2];
                m->planned.cartesian.orient.u3 = orient[3];
            }
        } else {
            return -1;
        }
        if (!pb_encode(&os, abb_egm_EgmSensor_fields, m)) return -1;
    }
    return (int)os.bytes_written;
}
