"""The RSI messages of the simulator against KUKA's format as a public driver reads and writes it.

Reference: ROS-Industrial's ``kuka_rsi_hw_interface`` (github.com/ros-industrial/kuka_experimental),
``include/kuka_rsi_hw_interface/rsi_state.h`` reads the robot's message as::

    TiXmlElement* rob = bufferdoc.FirstChildElement("Rob");
    TiXmlElement* AIPos_el = rob->FirstChildElement("AIPos");
    AIPos_el->Attribute("A1", &positions[0]); ... ("A6", &positions[5]);
    TiXmlElement* ASPos_el = rob->FirstChildElement("ASPos");   ... A1..A6
    TiXmlElement* RIst_el = rob->FirstChildElement("RIst");
    RIst_el->Attribute("X", &cart_position[0]); ... "Y", "Z", "A", "B", "C"
    TiXmlElement* RSol_el = rob->FirstChildElement("RSol");     ... X..C
    TiXmlElement* ipoc_el = rob->FirstChildElement("IPOC");
    ipoc = std::stoull(ipoc_el->FirstChild()->Value());

and ``include/kuka_rsi_hw_interface/rsi_command.h`` writes the reply as::

    TiXmlElement* root = new TiXmlElement("Sen");
    root->SetAttribute("Type", "ImFree");
    TiXmlElement* el = new TiXmlElement("AK");
    el->SetAttribute("A1", std::to_string(joint_position_correction[0])); ... "A6"
    el = new TiXmlElement("IPOC");
    el->LinkEndChild(new TiXmlText(std::to_string(ipoc)));

(its ``krl/KR_C4/ros_rsi_ethernet.xml`` names the axis correction ``AK``; the contract's
``AKorr`` and ``RKorr`` are the other usual tags). The tests read our ``<Rob>`` the driver's
way and parse a reply written the driver's way, plus hostile replies.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from gtmodel.robot_sim.rsi import compose_rob, compose_sen, parse_rob, parse_sen
from gtmodel.robot_sim.state import ReplyError, RobotState

STATE = RobotState(np.array([1800.5, -2.25, 1200.125, 10.0, -20.0, 30.0]), np.array([1800.0, -2.0, 1200.0, 10.0, -20.0, 30.0]),
                   np.array([1.0, -38.53, 107.42, 0.0, -60.0, 0.5]), np.array([1.5, -38.0, 107.0, 0.0, -60.0, 0.0]))


def _driver_reads(data: bytes) -> dict:
    """rsi_state.h's reading, element by element (FirstChildElement + Attribute)."""
    rob = ET.fromstring(data)
    assert rob.tag == "Rob"
    out = {tag: [float(rob.find(tag).get(a)) for a in names] for tag, names in (
        ("AIPos", ("A1", "A2", "A3", "A4", "A5", "A6")), ("ASPos", ("A1", "A2", "A3", "A4", "A5", "A6")),
        ("RIst", ("X", "Y", "Z", "A", "B", "C")), ("RSol", ("X", "Y", "Z", "A", "B", "C")))}
    out["IPOC"] = int(rob.find("IPOC").text)
    return out


def test_rob_reads_as_the_driver_reads_it():
    got = _driver_reads(compose_rob(STATE, 123456, delay=3))
    want = {"AIPos": STATE.joints_actual.tolist(), "ASPos": STATE.joints_setpoint.tolist(), "RIst": STATE.cart_actual.tolist(),
            "RSol": STATE.cart_setpoint.tolist(), "IPOC": 123456}
    assert got == want


def test_rob_has_the_type_and_the_delay_element():
    rob = ET.fromstring(compose_rob(STATE, 4, delay=7))
    assert (rob.get("Type"), rob.find("Delay").get("D")) == ("KUKA", "7")


def test_nan_fault_writes_a_nan_ist_x():
    ipoc, fields = parse_rob(compose_rob(STATE, 8, nan_field=True))
    assert ipoc == 8 and np.isnan(fields["RIst"][0]) and np.isfinite(fields["RIst"][1:]).all()


def _driver_writes(correction, ipoc) -> bytes:
    """rsi_command.h's reply: Sen Type="ImFree", AK with std::to_string (6 decimals), IPOC."""
    ak = " ".join(f'A{i + 1}="{v:f}"' for i, v in enumerate(correction))
    return f'<Sen Type="ImFree"><AK {ak} /><IPOC>{ipoc}</IPOC></Sen>'.encode()


def test_a_reply_written_as_the_driver_writes_it_parses():
    reply = parse_sen(_driver_writes([0.1, -0.2, 0.0, 0.0, 1.5, -3.0], 987654321))
    assert reply.ipoc == 987654321 and reply.rkorr is None and reply.akorr.tolist() == [0.1, -0.2, 0.0, 0.0, 1.5, -3.0]


def test_our_own_reply_round_trips_with_extra_elements_in_any_order():
    data = (b'<Sen Type="ImFree"><IPOC>44</IPOC><Extra a="1"><Deep/></Extra><EStr>hello</EStr>'
            b'<RKorr C="6" B="5" A="4" Z="3" Y="2" X="1"/></Sen>')
    reply = parse_sen(data)
    assert (reply.ipoc, reply.rkorr.tolist(), reply.estr) == (44, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0], "hello")
    assert parse_sen(compose_sen(12, [1, 2, 3, 0, 0, 0])).rkorr.tolist() == [1, 2, 3, 0, 0, 0]


HOSTILE = {
    "doctype": (b'<!DOCTYPE Sen [<!ENTITY a "aaaa"><!ENTITY b "&a;&a;&a;&a;">]><Sen Type="ImFree"><EStr>&b;</EStr><IPOC>1</IPOC></Sen>', "hostile"),
    "too_long": (b'<Sen Type="ImFree"><EStr>' + b"x" * 5000 + b"</EStr><IPOC>1</IPOC></Sen>", "too_long"),
    "not_xml": (b"\x00\xff\x10garbage", "malformed"),
    "truncated": (b'<Sen Type="ImFree"><RKorr X="1"', "malformed"),
    "other_root": (b'<Rob Type="KUKA"><IPOC>1</IPOC></Rob>', "malformed"),
    "other_type": (b'<Sen Type="Other"><IPOC>1</IPOC></Sen>', "malformed"),
    "no_ipoc": (b'<Sen Type="ImFree"><RKorr X="1"/></Sen>', "malformed"),
    "negative_ipoc": (b'<Sen Type="ImFree"><IPOC>-4</IPOC></Sen>', "malformed"),
    "huge_ipoc": (b'<Sen Type="ImFree"><IPOC>' + b"9" * 30 + b"</IPOC></Sen>", "malformed"),
    "nan": (b'<Sen Type="ImFree"><RKorr X="nan"/><IPOC>1</IPOC></Sen>', "nonfinite"),
    "inf": (b'<Sen Type="ImFree"><AKorr A1="-inf"/><IPOC>1</IPOC></Sen>', "nonfinite"),
    "out_of_range": (b'<Sen Type="ImFree"><RKorr X="1e300"/><IPOC>1</IPOC></Sen>', "out_of_range"),
    "not_a_number": (b'<Sen Type="ImFree"><RKorr X="1.2.3"/><IPOC>1</IPOC></Sen>', "malformed"),
    "deep": (b'<Sen Type="ImFree">' + b"<a>" * 500 + b"</a>" * 500 + b"</Sen>", "malformed"),
}


@pytest.mark.parametrize("name", sorted(HOSTILE))
def test_hostile_reply_is_rejected_with_its_reason(name):
    data, reason = HOSTILE[name]
    with pytest.raises(ReplyError) as info:
        parse_sen(data)
    assert info.value.reason == reason
