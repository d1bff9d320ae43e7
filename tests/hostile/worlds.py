"""A generator of hostile world files: each one is invalid, and says which line holds the offending element.

:func:`generate` writes every case into a directory and returns them; the tests run ``sigcore check`` (and a few
``sigcore run``) on each and assert a located message (``file:line``), exit code 2, no traceback, bounded time
and memory. The classes: XML attacks (XXE, entity expansion, XInclude, external DTD), huge and deeply nested
files, broken assets (meshes, URDFs), NaN and infinity everywhere, unknown elements and attributes, duplicate
and invalid names, names that collide with the ROS 2 transport's own topics.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

SIGBOT = Path(__file__).resolve().parents[2] / "worlds" / "models" / "sigbot" / "sigbot.urdf"
"""A real robot model, with a differential drive and a laser link."""

DRIVE = '<drive type="differential" left="wheel_l_joint" right="wheel_r_joint" radius="0.1" separation="0.4"/>'


@dataclass(frozen=True)
class Case:
    """One hostile world.

    Attributes:
        name: The case, e.g. ``xxe_file_entity``.
        path: The world file.
        line: The line of the offending element (the message must name ``path:line``).
        run: Also check that ``sigcore run`` refuses it, with this transport (``none`` or ``ros2``); None: only
            ``sigcore check``.
    """

    name: str
    path: Path
    line: int
    run: str | None = None


def _world(body: str, attrs: str = 'name="hostile"', head: str = "") -> str:
    return f'{head}<world {attrs}>\n  <object name="floor_box" shape="box" size="1 1 0.1" static="true"/>\n' \
           f"{body}\n</world>\n"


def _robot(children: str, name: str = "r", extra: str = "") -> str:
    return f'  <robot name="{name}" urdf="{SIGBOT}"{extra}>\n    {DRIVE}\n    {children}\n  </robot>'


def _urdf(links: str, joints: str = "", name: str = "bad") -> str:
    return f'<?xml version="1.0"?>\n<robot name="{name}">\n{links}\n{joints}\n</robot>\n'


def _link(name: str, mass: str = "1", inertia: str = 'ixx="0.01" iyy="0.01" izz="0.01"', extra: str = "") -> str:
    return (f'  <link name="{name}">\n    <inertial><mass value="{mass}"/>'
            f'<inertia {inertia} ixy="0" ixz="0" iyz="0"/></inertial>\n'
            f'    <collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision>{extra}\n  </link>')


def _chain(n: int) -> str:
    links = "\n".join(_link(f"l{i}") for i in range(n))
    joints = "\n".join(f'  <joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
                       f'<origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" '
                       f'velocity="1"/></joint>' for i in range(n - 1))
    return _urdf(links, joints)


def generate(directory: Path) -> list[Case]:
    """Write every hostile world (and the assets they use) into ``directory``; at least 60 cases.

    Returns:
        The cases, each with the line its message must name.
    """
    directory.mkdir(parents=True, exist_ok=True)
    secret = directory / "secret.txt"
    secret.write_text("TOP-SECRET-VALUE\n")
    cases: list[Case] = []

    def add(name: str, text: str | bytes, marker: str | None, run: str | None = None) -> None:
        """Write ``text``; the offending element is the line holding ``marker`` (line 1 if None)."""
        path = directory / f"{name}.xml"
        if isinstance(text, bytes):
            path.write_bytes(text)
            line = 1 if marker is None else text[:text.index(marker.encode())].count(b"\n") + 1
        else:
            path.write_text(text, encoding="utf-8")
            line = 1 if marker is None else text[:text.index(marker)].count("\n") + 1
        cases.append(Case(name, path, line, run))

    def asset(name: str, data: str | bytes) -> Path:
        path = directory / name
        if isinstance(data, bytes):
            path.write_bytes(data)
        else:
            path.write_text(data, encoding="utf-8")
        return path

    # ---------------------------------------------------------------- XML attacks
    add("xxe_file_entity", f'<!DOCTYPE world [<!ENTITY x SYSTEM "file://{secret}">]>\n'
        '<world name="w">\n  <object name="a" shape="box" size="&x;"/>\n</world>\n', "<object", run="none")
    add("xxe_in_text", f'<!DOCTYPE world [<!ENTITY x SYSTEM "file://{secret}">]>\n<world name="w">&x;</world>\n',
        None)
    add("internal_entity_in_text", '<!DOCTYPE world [<!ENTITY x "text">]>\n<world name="w">\n&x;</world>\n',
        None)
    laughs = "".join(f'<!ENTITY l{i} "{"".join(f"&l{i - 1};" for _ in range(10))}">' for i in range(1, 10))
    add("billion_laughs", f'<!DOCTYPE world [<!ENTITY l0 "lol">{laughs}]>\n<world name="w">&l9;</world>\n',
        None)
    add("billion_laughs_attribute", f'<!DOCTYPE world [<!ENTITY l0 "lol">{laughs}]>\n<world name="w">\n'
        '  <object name="a" shape="box" size="1 1 1" tags="&l9;"/>\n</world>\n', "<object")
    add("xinclude", _world(f'  <xi:include xmlns:xi="http://www.w3.org/2001/XInclude" href="{secret}" '
                           'parse="text"/>'), "<xi:include")
    add("external_dtd", '<!DOCTYPE world SYSTEM "http://127.0.0.1:9/evil.dtd">\n'
        + _world('  <object name="a" shape="box" size="1 1 1"/>'), "<!DOCTYPE")
    add("external_parameter_entity", f'<!DOCTYPE world [<!ENTITY % p SYSTEM "file://{secret}"> %p;]>\n'
        '<world name="w"/>\n', None)
    add("undefined_entity", "<world>&x;</world>\n", None)
    add("processing_instruction_text", _world('  <?php echo 1; ?>stray'), "<?php")
    add("cdata_text", _world("  <![CDATA[ <object/> ]]>"), "<![CDATA[")
    add("stray_text_world", _world("  some stray text"), "some stray")
    add("stray_text_robot", _world(_robot("words inside a robot")), "words inside")
    add("stray_text_leaf", _world('  <object name="a" shape="box" size="1 1 1">text</object>'), ">text<")
    add("not_xml_binary", bytes(range(128, 256)) * 8, None)
    add("empty_file", "", None)
    add("truncated", _world('  <object name="a" shape="box" size="1 1 1"/>')[:-20], '<object name="a"')
    add("not_utf8", b'<world name="w">\n  <object name="\xff\xfe" shape="box" size="1 1 1"/>\n</world>\n', "<object")
    add("wrong_root", '<robot name="r"/>\n', None)
    add("deep_nesting", "<world>" + "<object>" * 10_000 + "</object>" * 10_000 + "</world>", None)
    # ---------------------------------------------------------------- huge files
    add("huge_attribute", _world(f'  <object name="a" shape="box" size="1 1 1" tags="{"x" * 20_000_000}" '
                                 'bogus="1"/>'), "<object name=\"a\"")
    many = "\n".join(f'  <object name="o{i}" shape="sphere" size="0.1" pose="{i % 100} {i // 100} 1"/>'
                     for i in range(100_000))
    add("hundred_thousand_objects", _world(many + '\n  <object name="last" shape="sphere" size="-1"/>'),
        '<object name="last"')
    # ---------------------------------------------------------------- non-finite and absurd numbers
    for name, element in [
        ("nan_pose", '<object name="a" shape="box" size="1 1 1" pose="nan 0 0"/>'),
        ("inf_size", '<object name="a" shape="box" size="inf 1 1"/>'),
        ("nan_color", '<object name="a" shape="box" size="1 1 1" color="nan 0 0 1"/>'),
        ("inf_mass", '<object name="a" shape="box" size="1 1 1" mass="inf"/>'),
        ("nan_friction", '<object name="a" shape="box" size="1 1 1" friction="nan"/>'),
        ("huge_scale", f'<object name="a" urdf="{SIGBOT}" scale="1e308"/>'),
        ("tiny_scale", f'<object name="a" urdf="{SIGBOT}" scale="1e-300"/>'),
        ("inf_human_height", '<human name="h" height="inf"/>'),
        ("nan_robot_pose", f'<robot name="r" urdf="{SIGBOT}" pose="0 0 0 nan 0 0"/>'),
    ]:
        add(name, _world("  " + element), element, run="none" if name == "nan_pose" else None)
    add("nan_timestep", _world("", 'name="w" timestep="nan"'), "<world")
    add("inf_gravity", _world("", 'name="w" gravity="0 0 -inf"'), "<world")
    add("huge_gravity", _world("", 'name="w" gravity="0 0 -1e30"'), "<world", run="none")
    add("nan_lidar_range", _world(_robot('<lidar name="scan" link="base_laser_link" range="0.1 nan"/>')), "<lidar")
    add("inf_lidar_rate", _world(_robot('<lidar name="scan" link="base_laser_link" rate="inf"/>')), "<lidar")
    add("nan_drive_radius", _world(f'  <robot name="r" urdf="{SIGBOT}">\n    <drive type="differential" '
                                   'left="wheel_l_joint" right="wheel_r_joint" radius="nan" separation="0.4"/>\n'
                                   '  </robot>'), "<drive")
    add("inf_gains", _world(_robot('<gains kp="inf"/>')), "<gains")
    add("slam_origin_inf", _world(_robot("") + '\n  <plugin name="slam" agent="r" origin="inf inf"/>'),
        "<plugin", run="none")
    add("slam_resolution_nan", _world(_robot("") + '\n  <plugin name="slam" agent="r" resolution="nan"/>'),
        "<plugin")
    add("referee_time_limit_inf", _world('  <plugin name="referee" rules="cleanup" time_limit="inf"/>'), "<plugin")
    add("ros2_clock_rate_nan", _world('  <plugin name="ros2" clock_rate="nan"/>'), "<plugin")
    # ---------------------------------------------------------------- unknown elements and attributes
    add("unknown_element", _world('  <robto name="r"/>'), "<robto")
    add("unknown_attribute", _world('  <object name="a" shape="box" size="1 1 1" colour="1 0 0 1"/>'), "colour")
    add("unknown_lidar_attribute", _world(_robot('<lidar name="scan" link="base_laser_link" hz="10"/>')),
        "<lidar")
    add("unknown_plugin", _world('  <plugin name="no_such_feature"/>'), "<plugin")
    add("unknown_plugin_attribute", _world(_robot("") + '\n  <plugin name="slam" agent="r" colour="red"/>'),
        "<plugin")
    add("element_in_object", _world('  <object name="a" shape="box" size="1 1 1"><lidar/></object>'), "<lidar")
    # ---------------------------------------------------------------- names
    for name, bad in [("name_digit", "1robot"), ("name_dash", "a-b"), ("name_unicode", "robotä"),
                      ("name_space", "a b"), ("name_empty", ""), ("name_too_long", "a" * 65),
                      ("name_slash", "a/b"), ("name_tilde", "~a"), ("name_braces", "{a}")]:
        add(name, _world(f'  <object name="{bad}" shape="box" size="1 1 1"/>'), f'name="{bad}"')
    add("lidar_name_invalid", _world(_robot('<lidar name="scan-1" link="base_laser_link"/>')), "<lidar")
    add("arm_name_invalid", _world(_robot('<arm name="9arm" base="base_link" tip="base_link"/>')), "<arm")
    add("plugin_name_invalid", _world('  <plugin name="sl am"/>'), "<plugin")
    add("world_name_invalid", _world("", 'name="my world"'), "<world")
    add("duplicate_agents", _world('  <object name="floor_box" shape="box" size="1 1 1"/>'),
        '<object name="floor_box" shape="box" size="1 1 1"/>')
    add("duplicate_lidars", _world(_robot('<lidar name="scan" link="base_laser_link"/>\n'
                                          '    <lidar name="scan" link="base_link"/>')),
        '<lidar name="scan" link="base_link"')
    # ---------------------------------------------------------------- collisions with the transport's names
    for topic in ("odom", "cmd_vel", "joint_states"):
        add(f"lidar_named_{topic}", _world(_robot(f'<lidar name="{topic}" link="base_laser_link"/>')), "<lidar",
            run="ros2" if topic == "odom" else None)
    add("robot_sigcore_lidar_ready", _world(f'  <robot name="sigcore" urdf="{SIGBOT}">\n'
                                            '    <lidar name="ready" link="base_laser_link"/>\n  </robot>'), "<lidar",
        run="ros2")
    add("lidar_named_slam_pose", _world(_robot('<lidar name="slam_pose" link="base_laser_link"/>')
                                        + '\n  <plugin name="slam" agent="r"/>'), "<lidar")
    # ---------------------------------------------------------------- broken assets
    meshes: list[tuple[str, str | bytes]] = [
        ("mesh_empty.stl", b""),
        ("mesh_garbage.stl", b"\x00\x01garbage" * 50),
        ("mesh_truncated.stl", b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0"),
        ("mesh_truncated_binary.stl", b"\x00" * 80 + (1000).to_bytes(4, "little") + b"\x00" * 30),
        ("mesh_garbage.obj", b"v 1 2\nf 1 2 3 4 5\nv nan nan nan\nf 9 9 9\n"),
        ("mesh_text.obj", "this is not a mesh\n" * 10),
        ("mesh_degenerate.obj", "v 0 0 0\n" * 4 + "f 1 2 3\nf 1 2 4\n"),  # passes the core, the engine refuses
    ]
    for file, data in meshes:
        mesh = asset(file, data)
        stem = file.replace(".", "_")
        add(f"object_{stem}", _world(f'  <object name="m" mesh="{mesh.name}"/>'), '<object name="m"',
            run="none" if file == "mesh_garbage.stl" else None)
    add("mesh_missing", _world('  <object name="m" mesh="no_such.stl"/>'), '<object name="m"')
    add("path_too_long", _world(f'  <object name="m" mesh="{"d" * 5000}.stl"/>'), '<object name="m"')
    add("path_part_too_long", _world(f'  <object name="m" mesh="x/{"d" * 300}.stl"/>'), '<object name="m"')
    urdfs: list[tuple[str, str]] = [
        ("urdf_not_xml", "this is not xml <<<"),
        ("urdf_wrong_root", "<model/>"),
        ("urdf_negative_mass", _urdf(_link("base", mass="-1"))),
        ("urdf_nan_mass", _urdf(_link("base", mass="nan"))),
        ("urdf_negative_inertia", _urdf(_link("base", inertia='ixx="-1" iyy="0.01" izz="0.01"'))),
        ("urdf_nan_inertia", _urdf(_link("base", inertia='ixx="nan" iyy="0.01" izz="0.01"'))),
        ("urdf_duplicate_links", _urdf(_link("base") + "\n" + _link("base"))),
        ("urdf_duplicate_joints", _urdf(_link("a") + _link("b") + _link("c"),
                                        '<joint name="j" type="fixed"><parent link="a"/><child link="b"/></joint>\n'
                                        '<joint name="j" type="fixed"><parent link="a"/><child link="c"/></joint>')),
        ("urdf_missing_mesh", _urdf(_link("base", extra='<visual><geometry><mesh filename="nope.stl"/></geometry>'
                                                        '</visual><collision><geometry><mesh filename="nope.stl"/>'
                                                        '</geometry></collision>'))),
        ("urdf_chain_2000", _chain(2000)),
        ("urdf_xxe", f'<!DOCTYPE robot [<!ENTITY x SYSTEM "file://{secret}">]>\n'
                     f'<robot name="x"><link name="&x;"/></robot>'),
        ("urdf_inf_origin", _urdf('  <link name="base"><visual><origin xyz="inf 0 0"/><geometry><box size="1 1 1"/>'
                                  "</geometry></visual></link>")),
        ("urdf_zero_box", _urdf('  <link name="base"><collision><geometry><box size="0 1 1"/></geometry>'
                                "</collision></link>")),
        ("urdf_no_links", _urdf("")),
        ("urdf_garbage_mesh", _urdf(_link("base", extra='<collision><geometry><mesh filename="mesh_garbage.stl"/>'
                                                        '</geometry></collision>'))),
    ]
    for name, text in urdfs:
        urdf = asset(f"{name}.urdf", text)
        add(f"object_{name}", _world(f'  <object name="u" urdf="{urdf.name}"/>'), '<object name="u"',
            run="none" if name in ("urdf_chain_2000", "urdf_missing_mesh") else None)
    add("robot_urdf_negative_mass", _world('  <robot name="rb" urdf="urdf_negative_mass.urdf"/>'),
        '<robot name="rb"')
    return cases
