"""A sensor side written with ``abb-robot-client``'s EGM class (an independent, well-kept client).

Run as a script in its own process (``abb_robot_client`` registers its own ``egm.proto`` in
protobuf's default descriptor pool, which clashes with ``gtmodel._egm_pb2``'s copy: the two
cannot be imported in one process)::

    python abb_egm_client.py CYCLES OUT.json

It binds 127.0.0.1 on a free port, prints the port on stdout, then for each robot message
records the fed-back joints and the header's seqno and answers with ``send_to_robot`` a
joint command (the first fed-back joints plus a 0.5 Hz sine of 2 mm on each axis), until
CYCLES messages or 5 s without one; it writes what it received and sent to OUT.json.
"""

import json
import math
import socket
import sys

from abb_robot_client.egm import EGM


def main() -> int:
    cycles, out = int(sys.argv[1]), sys.argv[2]
    egm = EGM(port=0)
    egm.socket.close()  # the class binds every interface: rebind on the loopback only
    egm.socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    egm.socket.bind(("127.0.0.1", 0))
    print(egm.socket.getsockname()[1], flush=True)
    received, sent, q0 = [], [], None
    while len(received) < cycles:
        ok, state = egm.receive_from_robot(timeout=5.0)
        if not ok:
            break
        joints = [float(v) for v in state.joint_angles]
        seqno = int(state.robot_message.header.seqno)
        q0 = joints if q0 is None else q0
        t = len(received) * 0.004
        command = [q + 2.0 * math.sin(2 * math.pi * 0.5 * t) for q in q0]
        egm.send_to_robot(command)
        received.append({"seqno": seqno, "joints": joints, "motors_on": bool(state.motors_on), "rapid_running": bool(state.rapid_running)})
        sent.append(command)
    with open(out, "w", encoding="utf-8") as fh:
        json.dump({"received": received, "sent": sent}, fh)
    return 0


if __name__ == "__main__":
    sys.exit(main())
