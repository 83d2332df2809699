"""Unit tests of proto/idl2py.py: the parser, the generated module and its rejections."""

from __future__ import annotations

import dataclasses
import importlib.util
import subprocess
import sys
import types as pytypes
import typing
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
IDL = REPO / "proto" / "surfeledit.idl"
sys.path.insert(0, str(REPO / "proto"))

import idl2py  # noqa: E402


def load_module(source: str, name: str) -> pytypes.ModuleType:
    """Executes generated source as a fresh module (cyclonedds resolves annotations via sys.modules)."""
    module = pytypes.ModuleType(name)
    sys.modules[name] = module
    exec(compile(source, f"<{name}>", "exec", dont_inherit=True), module.__dict__)
    return module


@pytest.fixture(scope="module")
def proto() -> pytypes.ModuleType:
    return load_module(idl2py.generate_file(IDL), "_generated_surfeledit_proto")


def annotated_name(tp: typing.Any) -> str:
    """The cyclonedds spelling of a member's annotation (e.g. 'uint64', 'sequence[float64]')."""
    args = typing.get_args(tp)
    if args:  # Annotated[base, marker]
        return str(args[1])
    return tp.__name__


def field_types(cls: type) -> dict:
    hints = typing.get_type_hints(cls, include_extras=True)
    return {f.name: annotated_name(hints[f.name]) for f in dataclasses.fields(cls)}


def test_parses_every_definition_in_order() -> None:
    spec = idl2py.parse(IDL.read_text(), str(IDL))
    names = [d.name for d in spec.definitions]
    assert names[:4] == ["Status", "Op", "SelectorKind", "Vec3"]
    assert names[-1] == "Update"
    assert all(d.scoped.startswith("surfeledit::proto::") for d in spec.definitions)
    # Dependencies are always defined before use.
    seen: set = set()
    for d in spec.definitions:
        if isinstance(d, idl2py.Struct):
            for m in d.members:
                t = m.type.element if isinstance(m.type, idl2py.Sequence_) else m.type
                if isinstance(t, idl2py.Named):
                    assert t.scoped in seen
        seen.add(d.scoped)


def test_enums(proto: pytypes.ModuleType) -> None:
    assert proto.Status.STATUS_OK.value == 0
    assert proto.Status.STATUS_INTERNAL.value == 6
    assert proto.Op.OP_GET_STATE.value == 10
    assert [e.name for e in proto.SelectorKind] == ["SELECTOR_SPHERE", "SELECTOR_BOX"]
    # Members are ints too, so that they can be the value of a long field.
    assert isinstance(proto.Op.OP_DEFORM, int) and proto.Op.OP_DEFORM == 9
    assert proto.SettingKind(3) is proto.SettingKind.SETTING_INT


def test_enum_members_in_long_fields_serialize_as_their_numbers(proto: pytypes.ModuleType) -> None:
    typed = proto.Request(client_id="c", request_id=1, op=proto.Op.OP_CURVES)
    raw = proto.Request(client_id="c", request_id=1, op=int(proto.Op.OP_CURVES))
    assert typed.serialize() == raw.serialize()
    back = proto.Request.deserialize(proto.Request(client_id="c", request_id=2, op=99).serialize())
    assert back.op == 99  # a value outside the enum survives the wire (the server then refuses it by name)


def test_struct_fields_and_types(proto: pytypes.ModuleType) -> None:
    assert field_types(proto.Vec3) == {"x": "float64", "y": "float64", "z": "float64"}
    assert field_types(proto.LoadBegin) == {"total": "uint64", "has_radii": "bool"}
    sinfo = field_types(proto.SessionInfo)
    assert sinfo["clients"] == "uint32"
    assert sinfo["bytes_per_surfel"] == "float64"
    assert sinfo["structures"].startswith("sequence[") and "Structure" in sinfo["structures"]
    req = field_types(proto.Request)
    assert list(req) == ["client_id", "request_id", "session", "op", "load_begin", "load_chunk",
                         "load_file", "set_regions", "deform", "get_state", "configure", "remove", "merge", "curves",
                         "invite", "token", "blend", "boolean_op", "fill_holes", "expect_version"]
    assert req["expect_version"] == "sequence[uint64]"
    # Enum-valued request fields travel as long (proto/surfeledit.idl): unknown values still arrive.
    assert req["client_id"] == "str" and req["op"] == "int32"
    assert field_types(proto.Selector)["kind"] == "int32" and field_types(proto.Setting)["kind"] == "int32"
    assert field_types(proto.Update)["ids"] == "sequence[uint64]"
    assert field_types(proto.Update)["part"] == "uint32"


def test_keys(proto: pytypes.ModuleType) -> None:
    def annotated(cls: type) -> dict:
        # Serializing fills in empty entries for the other fields: only the non-empty ones matter.
        return {k: v for k, v in cls.__idl_field_annotations__.items() if v}
    assert annotated(proto.Request) == {"client_id": {"key": True}}
    assert annotated(proto.Reply) == {"client_id": {"key": True}}
    assert annotated(proto.Update) == {"session": {"key": True}}
    assert proto.Request.__idl_typename__ == "surfeledit.proto.Request"


def test_defaults_are_fresh_and_zero(proto: pytypes.ModuleType) -> None:
    a, b = proto.Reply(), proto.Reply()
    a.timings.append(proto.Timing("total", 1.0))
    assert b.timings == []
    assert b.status == proto.Status.STATUS_OK and b.field == ""
    assert proto.Deform().axis == proto.Vec3(0.0, 0.0, 0.0)


def test_serialization_round_trip(proto: pytypes.ModuleType) -> None:
    req = proto.Request(
        client_id="c", request_id=2**63 + 5, session="s", op=proto.Op.OP_SET_REGIONS,
        set_regions=[proto.SetRegions(
            zero=proto.RegionSpec(ids=[1, 2, 3]),
            one=proto.RegionSpec(selectors=[proto.Selector(proto.SelectorKind.SELECTOR_BOX,
                                                           proto.Vec3(1, 2, 3), 0.5, proto.Vec3(4, 5, 6))]))])
    assert proto.Request.deserialize(req.serialize()) == req


def test_fixed_arrays_and_nested_modules() -> None:
    src = """
    // comment
    module a { module b {
      @final enum E { E_X, E_Y };
      @final struct P { double v[3]; E e; };
    }; // inner
    @final struct Q { @key string name; b::P p; sequence<a::b::P> ps; unsigned long long n, m; };
    };
    """
    spec = idl2py.parse(src, "t.idl")
    mod = load_module(idl2py.generate(spec), "_generated_array_test")
    assert field_types(mod.P)["v"] == "array[float64, 3]"
    assert mod.P().v == [0.0, 0.0, 0.0]
    assert mod.Q.__idl_typename__ == "a.Q"
    assert mod.P.__idl_typename__ == "a.b.P"
    assert field_types(mod.Q)["n"] == "uint64" and field_types(mod.Q)["m"] == "uint64"
    q = mod.Q(name="k", p=mod.P([1.0, 2.0, 3.0], mod.E.E_Y), ps=[mod.P()], n=1, m=2)
    assert mod.Q.deserialize(q.serialize()) == q


@pytest.mark.parametrize("src, line, what", [
    ("module m { union U switch (long) { case 1: long a; }; };", 1, "'union' is not supported"),
    ("struct S { long a; };\ntypedef long T;", 2, "'typedef' is not supported"),
    ("struct S {\n  sequence<long, 4> a;\n};", 2, "bounded sequences"),
    ("struct S {\n  string<8> a;\n};", 2, "bounded strings"),
    ("struct S {\n  Unknown a;\n};", 2, "unknown type 'Unknown'"),
    ("struct S { T a; };\nstruct T { long b; };", 1, "unknown type 'T'"),
    ("@appendable struct S { long a; };", 1, "@appendable is not supported"),
    ("struct S {\n  @optional long a;\n};", 2, "@optional is not supported"),
    ("@final(true) struct S { long a; };", 1, "annotation arguments"),
    ("/* c */ struct S { long a; };", 1, "block comments"),
    ("#include \"x.idl\"\n", 1, "preprocessor"),
    ("struct S {\n long a[2][3];\n};", 2, "multi-dimensional"),
    ("struct S {\n long a[N];\n};", 2, "decimal literal"),
    ("struct S { long a; long a; };", 1, "appears twice"),
    ("struct S { long a; };\nstruct S { long b; };", 2, "defined twice"),
    ("enum E { A = 1 };", 1, "expected ',' or '}'"),
    ("struct S { long double x; };", 1, "'long double'"),
    ("struct S { wstring x; };", 1, "not supported"),
    ("struct S { long a }", 1, "expected ';'"),
    ("struct S { long a; };\nconst long N = 3;", 2, "'const' is not supported"),
    ("module m { struct S { long a; }; };\nmodule n { struct S { long b; }; };", 2, "collides"),
    ("struct S { long class; };", 1, "Python"),
    ("struct S { long a; } ;\n\n  $", 3, "unexpected character '$'"),
])
def test_unsupported_constructs_fail_loudly(src: str, line: int, what: str) -> None:
    with pytest.raises(idl2py.IdlError) as info:
        idl2py.parse(src, "bad.idl")
    assert info.value.file == "bad.idl"
    assert info.value.line == line, str(info.value)
    assert what in str(info.value)
    assert str(info.value).startswith(f"bad.idl:{line}: ")


def test_command_line(tmp_path: Path) -> None:
    out = tmp_path / "pkg" / "_proto.py"
    subprocess.run([sys.executable, str(REPO / "proto" / "idl2py.py"), str(IDL), "-o", str(out)], check=True)
    spec = importlib.util.spec_from_file_location("_cli_generated_proto", out)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    sys.modules["_cli_generated_proto"] = mod
    spec.loader.exec_module(mod)
    assert mod.Request().op == mod.Op.OP_INFO

    bad = tmp_path / "bad.idl"
    bad.write_text("struct S {\n  any x;\n};\n")
    res = subprocess.run([sys.executable, str(REPO / "proto" / "idl2py.py"), str(bad), "-o", str(tmp_path / "x.py")],
                         capture_output=True, text=True)
    assert res.returncode == 1
    assert f"{bad}:2:" in res.stderr
    assert not (tmp_path / "x.py").exists()
