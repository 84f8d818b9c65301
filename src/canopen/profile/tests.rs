use super::*;

fn frame(data: &[u8]) -> Emcy {
    Emcy::decode(data).expect("test frames carry code and register")
}

fn int(v: u64) -> FieldValue {
    FieldValue::Int(v)
}

fn text(t: &str) -> FieldValue {
    FieldValue::Text(t.to_owned())
}

fn profile(name: &str) -> &'static Profile {
    Profile::builtin(name).unwrap_or_else(|| panic!("no built-in {name}"))
}

#[test]
fn only_profiles_with_a_category_field_or_rows_have_categories() {
    assert!(profile("kollmorgen").has_categories());
    for name in ["cia301", "cia402", "canopennode"] {
        assert!(!profile(name).has_categories(), "{name}");
    }
}

/// The CiA 301 checks, then the profile's, as the consumer runs them.
fn all_warnings(p: &Profile, data: &[u8]) -> Vec<&'static str> {
    let emcy = frame(data);
    let mut out = Vec::new();
    emcy.frame_warnings(&p.info(emcy.code), &mut out);
    p.frame_warnings(&emcy, &mut out);
    out.iter().map(Warning::tag).collect()
}

#[test]
fn profiles_take_back_what_their_manual_shows_as_normal() {
    // The S300 manual's 10 43 08 01: the temperature bit without bit 0.
    let s300 = [0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0];
    assert_eq!(all_warnings(profile("cia402"), &s300), ["no_generic_bit"]);
    assert!(all_warnings(profile("kollmorgen"), &s300).is_empty());
    // STÖBER's 0x4310 with register 0x01, E82 = 41.
    let stoeber = [0x10, 0x43, 0x01, 0x29, 0, 0, 0, 0];
    assert_eq!(
        all_warnings(profile("cia402"), &stoeber),
        ["class_register_mismatch"]
    );
    assert!(all_warnings(profile("stoeber"), &stoeber).is_empty());
    // Each profile keeps the other check.
    assert_eq!(
        all_warnings(profile("kollmorgen"), &[0x10, 0x43, 0x04, 0x01, 0, 0, 0, 0]),
        ["class_register_mismatch"]
    );
    assert_eq!(
        all_warnings(profile("stoeber"), &[0x10, 0x43, 0x08, 0x29, 0, 0, 0, 0]),
        ["no_generic_bit"]
    );
}

#[test]
fn register_keys_are_inherited_and_can_be_set_back() {
    let s300 = [0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0];
    let child = Profile::parse("t", "name = \"x\"\nbase = \"kollmorgen\"\n").unwrap();
    assert!(all_warnings(&child, &s300).is_empty());
    let strict = Profile::parse(
        "t",
        "name = \"x\"\nbase = \"kollmorgen\"\nregister_generic_bit = true\n",
    )
    .unwrap();
    assert_eq!(all_warnings(&strict, &s300), ["no_generic_bit"]);
    let lax = Profile::parse("t", "name = \"x\"\nregister_class_bits = false\n").unwrap();
    assert!(all_warnings(&lax, &[0x10, 0x43, 0x01, 0, 0, 0, 0, 0]).is_empty());
    assert!(Profile::parse("t", "name = \"x\"\nregister_class_bits = \"no\"\n").is_err());
}

fn warnings(p: &Profile, data: &[u8]) -> Vec<Warning> {
    let mut out = Vec::new();
    p.frame_warnings(&frame(data), &mut out);
    out
}

fn parse_err(text: &str) -> ProfileError {
    match Profile::parse("bad.toml", text) {
        Ok(p) => panic!("parsed: {p:?}"),
        Err(e) => e,
    }
}

#[test]
fn every_builtin_parses_in_listing_order() {
    let names: Vec<&str> = Profile::builtins().iter().map(Profile::name).collect();
    assert_eq!(
        names,
        [
            "cia301",
            "cia402",
            "kollmorgen",
            "beckhoff-ax2000",
            "stoeber",
            "festo-cmmp",
            "canopennode"
        ]
    );
    for (file, text) in BUILTIN_FILES {
        let p = Profile::parse(file, text).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(format!("{}.toml", p.name()), file);
        // The same profile whichever way it was loaded.
        assert_eq!(Profile::builtin(p.name()), Some(&p));
        assert!(!p.summary().is_empty() && !p.summary().contains('\n'));
    }
    assert_eq!(
        Profile::builtin(DEFAULT_PROFILE).map(Profile::tables),
        Some(Tables::Cia402)
    );
    assert!(Profile::builtin("nonsense").is_none());
    assert!(Profile::builtin("").is_none());
}

#[test]
fn generic_profiles_decode_nothing_and_keep_the_cia_text() {
    let cia402 = profile("cia402");
    let cia301 = profile("cia301");
    let e = frame(&[0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0]);
    for p in [cia301, cia402] {
        assert_eq!(p.decode_manufacturer(&e), None);
        assert_eq!(p.category(&e), None);
        assert_eq!(p.status_bit(&e), None);
        assert_eq!(p.vendor_code(0x4310), None);
        assert_eq!(p.register_bit_name(1), None);
        assert!(warnings(p, &[0x10, 0x43, 0x89, 1, 2, 3, 4, 5]).is_empty());
    }
    // cia402 describes exactly as codes.rs does.
    for code in [0x4310, 0x5100, 0x8130, 0xFF01, 0x1234, 0x0000] {
        assert_eq!(
            cia402.describe(code),
            codes::lookup(code).description().to_string()
        );
        assert_eq!(cia402.info(code), codes::lookup(code));
    }
    assert_eq!(cia301.describe(0x4310), "Temperature (0x4310 not listed)");
    assert_eq!(cia301.info(0x5100).class, Class::Undefined);
    assert_eq!(cia402.info(0x5100).class, Class::Hardware);
}

#[test]
fn kollmorgen_s300_example() {
    let p = profile("kollmorgen");
    let e = frame(&[0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0]);
    let d = p.decode_manufacturer(&e).expect("category byte");
    assert_eq!(
        d.fields,
        [
            ("category".to_owned(), int(1)),
            (
                "category_text".to_owned(),
                text(
                    "cleared only by a reset (COLDSTART command or control word bit 7); the front panel blinks Fxx"
                )
            ),
        ]
    );
    assert_eq!(p.category(&e), Some(1));
    assert_eq!(p.describe(0x4310), "F06 motor temperature (AKD: F235)");
    assert_eq!(
        p.vendor_code(0x4310),
        Some(&VendorCode {
            text: "motor temperature (AKD: F235)".to_owned(),
            category: Some(1),
            fault: Some("F06".to_owned()),
        })
    );
    assert_eq!(p.describe(0x1080), "no BTB/RTO (AKD: general warning)");
    // Codes without a row keep the CiA 402 text.
    assert_eq!(
        p.describe(0x8611),
        codes::lookup(0x8611).description().to_string()
    );
    assert!(warnings(p, &[0x10, 0x43, 0x08, 0x01, 0, 0, 0, 0]).is_empty());
    assert_eq!(
        warnings(p, &[0x10, 0x43, 0x08, 0x01, 0, 7, 0, 9]),
        [Warning::ManufacturerBytesNonZero { first: 5, last: 7 }]
    );

    // The reset that follows: category byte 0 is no category.
    let reset = frame(&[0, 0, 0x08, 0, 0, 0, 0, 0]);
    assert_eq!(
        p.decode_manufacturer(&reset).map(|d| d.fields),
        Some(vec![("category".to_owned(), int(0))])
    );
    assert_eq!(p.category(&reset), None);
    // A short frame without byte 3 falls back to the code row's category.
    let short = frame(&[0x10, 0x43, 0x08]);
    assert_eq!(p.decode_manufacturer(&short), None);
    assert_eq!(p.category(&short), Some(1));
    assert_eq!(p.category(&frame(&[0x10, 0x43, 0x08, 9])), Some(1));
    assert_eq!(p.category(&frame(&[0x10, 0x43, 0x08, 5])), Some(5));
}

#[test]
fn beckhoff_ax2000_numbering_rule() {
    let p = profile("beckhoff-ax2000");
    let e = frame(&[0x80, 0x43, 0x09, 0x02, 0, 0, 0, 0]);
    assert_eq!(p.category(&e), Some(2));
    assert_eq!(
        p.decode_manufacturer(&e)
            .and_then(|d| d.get("category_text").cloned()),
        Some(text("cleared by control word bit 11"))
    );
    assert_eq!(
        p.describe(0x4380),
        "Temperature · manufacturer-specific (low byte 0x80-0xFF)"
    );
    assert_eq!(
        p.describe(0x1180),
        "manufacturer-specific (low byte 0x80-0xFF)"
    );
    assert_eq!(
        p.describe(0x4310),
        codes::lookup(0x4310).description().to_string()
    );
    assert_eq!(
        p.describe(0x0080),
        codes::lookup(0x0080).description().to_string()
    );
    assert_eq!(
        p.describe(0xFF80),
        codes::lookup(0xFF80).description().to_string()
    );
    // The Kollmorgen numbering does not have the rule.
    assert_eq!(
        profile("kollmorgen").describe(0x4380),
        codes::lookup(0x4380).description().to_string()
    );
}

#[test]
fn stoeber_fault_41_and_its_exit() {
    let p = profile("stoeber");
    let enter = frame(&[0x10, 0x43, 0x01, 0x29, 0, 0, 0, 0]);
    assert_eq!(
        p.decode_manufacturer(&enter).map(|d| d.fields),
        Some(vec![
            ("event".to_owned(), int(41)),
            ("event_text".to_owned(), text("Temperature motor TMS")),
            ("cause".to_owned(), int(0)),
        ])
    );
    let exit = frame(&[0x00, 0x00, 0x00, 0x1E, 0, 0, 0, 0]);
    assert_eq!(
        p.decode_manufacturer(&exit).map(|d| d.fields),
        Some(vec![
            ("event".to_owned(), int(0x1E)),
            ("event_text".to_owned(), text("no error")),
            ("cause".to_owned(), int(0)),
        ])
    );
    assert_eq!(p.category(&enter), None);
    assert!(warnings(p, &[0x10, 0x43, 0x01, 0x29, 0x03, 0, 0, 0]).is_empty());
    assert_eq!(
        warnings(p, &[0x10, 0x43, 0x01, 0x29, 0, 0, 1, 0]),
        [Warning::ManufacturerBytesNonZero { first: 6, last: 6 }]
    );
    // An event number the profile does not name: number only.
    assert_eq!(
        p.decode_manufacturer(&frame(&[0x10, 0x43, 0x01, 0x30]))
            .map(|d| d.fields),
        Some(vec![("event".to_owned(), int(0x30))])
    );
}

#[test]
fn festo_rules() {
    let p = profile("festo-cmmp");
    // fixtures/festo.log: byte 6 is 0x12.
    assert_eq!(
        warnings(p, &[0x10, 0x43, 0x09, 0, 0, 0, 0x12, 0]),
        [Warning::ManufacturerBytesNonZero { first: 6, last: 6 }]
    );
    assert_eq!(
        warnings(p, &[0x10, 0x43, 0x09, 1, 0, 0, 0, 0]),
        [Warning::ManufacturerBytesNonZero { first: 3, last: 3 }]
    );
    assert!(warnings(p, &[0x10, 0x43, 0x09, 0, 0, 0, 0, 0]).is_empty());
    assert!(
        warnings(p, &[0x10, 0x43, 0x09]).is_empty(),
        "short: nothing to check"
    );
    // Bit 7 is Festo's reserved bit; bit 6 is left to the CiA 301 check.
    assert_eq!(
        warnings(p, &[0x10, 0x43, 0xC9, 0, 0, 0, 0, 0]),
        [Warning::ProfileReservedBit { bit: 7 }]
    );
    assert_eq!(p.register_bit_name(1), Some("I2t"));
    assert_eq!(p.register_bit_name(2), Some("voltage monitoring"));
    assert_eq!(p.register_bit_name(3), Some("motor over-temperature"));
    assert_eq!(p.register_bit_name(0), None);
    assert_eq!(p.register_bit_name(8), None);
    assert_eq!(
        p.decode_manufacturer(&frame(&[0x10, 0x43, 0x09, 0, 0, 0, 0, 0])),
        None
    );
}

#[test]
fn canopennode_status_bits() {
    let p = profile("canopennode");
    let warning = frame(&[0x00, 0x00, 0x11, 0x01, 0, 0, 0, 0]);
    assert_eq!(p.status_bit(&warning), Some(0x01));
    assert_eq!(
        p.decode_manufacturer(&warning).map(|d| d.fields),
        Some(vec![
            ("status_bit".to_owned(), int(1)),
            (
                "status_bit_text".to_owned(),
                text("CAN bus warning limit reached")
            ),
            ("info_code".to_owned(), int(0)),
        ])
    );
    // Heartbeat consumer timeout with info code 5 (little-endian).
    let hb = frame(&[0x30, 0x81, 0x11, 0x1B, 0x05, 0x00, 0x00, 0x01]);
    assert_eq!(p.status_bit(&hb), Some(0x1B));
    let d = p.decode_manufacturer(&hb).expect("fields");
    assert_eq!(
        d.get("status_bit_text"),
        Some(&text("heartbeat consumer timeout"))
    );
    assert_eq!(d.get("info_code"), Some(&int(0x0100_0005)));
    assert_eq!(
        p.decode_manufacturer(&frame(&[0, 0, 0, 0x35]))
            .map(|d| d.fields),
        Some(vec![
            ("status_bit".to_owned(), int(0x35)),
            (
                "status_bit_text".to_owned(),
                text("manufacturer error (information)")
            ),
        ])
    );
    assert_eq!(p.status_bit(&frame(&[0, 0, 0])), None);
    assert_eq!(p.tables(), Tables::Cia301);
    assert!(warnings(p, &[0, 0, 0, 1, 1, 2, 3, 4]).is_empty());
    for other in Profile::builtins()
        .iter()
        .filter(|p| p.name() != "canopennode")
    {
        assert_eq!(other.status_bit(&warning), None, "{}", other.name());
    }
}

#[test]
fn identity_picks_a_profile() {
    let pick = |dt, vid| for_identity(dt, vid).map(|(p, why)| (p.name(), why));
    assert_eq!(
        pick(Some(0x0002_0192), Some(0x6A)),
        Some(("kollmorgen", "vendor id 0x0000006A (Kollmorgen)".to_owned()))
    );
    assert_eq!(
        pick(None, Some(0xB9)),
        Some(("stoeber", "vendor id 0x000000B9 (STÖBER)".to_owned()))
    );
    assert_eq!(
        pick(Some(402), Some(0x1D)),
        Some(("festo-cmmp", "vendor id 0x0000001D (Festo)".to_owned()))
    );
    assert_eq!(
        pick(Some(0x0002_0192), Some(0x1234)),
        Some(("cia402", "device type 402 (drive)".to_owned()))
    );
    // A Festo valve terminal (device type 5001) is not a CMMP drive.
    assert_eq!(
        pick(Some(5001), Some(0x1D)),
        Some(("cia301", "device type 5001 (not a drive)".to_owned()))
    );
    assert_eq!(
        pick(Some(0x000F_0191), None),
        Some(("cia301", "device type 401 (not a drive)".to_owned()))
    );
    assert_eq!(pick(None, Some(0x1234)), None);
    assert_eq!(pick(None, Some(2)), None, "Beckhoff's id is not mapped");
    assert_eq!(pick(None, None), None);
}

const ACME: &str = include_str!("../../../fixtures/profiles/acme-servo.toml");

#[test]
fn the_example_user_profile_extends_kollmorgen() {
    let p = Profile::parse("acme-servo.toml", ACME).unwrap_or_else(|e| panic!("{e}"));
    let base = profile("kollmorgen");
    assert_eq!(p.name(), "acme-servo");
    assert_eq!(p.base(), Some("kollmorgen"));
    assert_eq!(p.tables(), Tables::Cia402);
    // Overridden row.
    assert_eq!(p.describe(0x4310), "F06 motor winding over-temperature");
    // Added row.
    assert_eq!(
        p.vendor_code(0xFF01),
        Some(&VendorCode {
            text: "brake feedback lost".to_owned(),
            category: Some(2),
            fault: Some("E17".to_owned()),
        })
    );
    // Inherited row.
    assert_eq!(p.vendor_code(0x3110), base.vendor_code(0x3110));
    // The category field is inherited; the drive field takes byte 4 out
    // of the base's zero bytes.
    let e = frame(&[0x10, 0x43, 0x89, 0x01, 0x02, 0, 0, 0]);
    assert_eq!(
        p.decode_manufacturer(&e).map(|d| d.fields),
        Some(vec![
            ("category".to_owned(), int(1)),
            (
                "category_text".to_owned(),
                text(
                    "cleared only by a reset (COLDSTART command or control word bit 7); the front panel blinks Fxx"
                )
            ),
            ("axis".to_owned(), int(2)),
            ("axis_text".to_owned(), text("axis B")),
        ])
    );
    assert!(warnings(&p, &[0x10, 0x43, 0x89, 0x01, 0x02, 0, 0, 0]).is_empty());
    assert_eq!(
        warnings(base, &[0x10, 0x43, 0x89, 0x01, 0x02, 0, 0, 0]),
        [Warning::ManufacturerBytesNonZero { first: 4, last: 4 }]
    );
    assert_eq!(
        warnings(&p, &[0x10, 0x43, 0x89, 0x01, 0x02, 0, 0, 0x40]),
        [Warning::ManufacturerBytesNonZero { first: 7, last: 7 }]
    );
    assert_eq!(p.register_bit_name(7), Some("drive fault"));
    assert_eq!(p.category(&frame(&[0x01, 0xFF, 0x81])), Some(2));
    // The user profile does not change the built-in.
    assert_eq!(base.describe(0x4310), "F06 motor temperature (AKD: F235)");
}

#[test]
fn load_file_reads_and_names_the_path() {
    let dir = tempfile::tempdir().expect("temp dir");
    let good = dir.path().join("acme.toml");
    std::fs::write(&good, ACME).expect("write");
    assert_eq!(
        Profile::load(&good).map(|p| p.name().to_owned()),
        Ok("acme-servo".to_owned())
    );

    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "name = \"x\"\nbase = \"cia402\"\nsize = 3\n").expect("write");
    let e = Profile::load(&bad).expect_err("unknown key");
    assert_eq!(e.line(), Some(3));
    assert!(
        e.to_string().starts_with(&format!("{}:3: ", bad.display())),
        "{e}"
    );

    let missing = dir.path().join("missing.toml");
    let e = Profile::load(&missing).expect_err("no file");
    assert_eq!(e.line(), None);
    assert!(
        e.to_string()
            .starts_with(&format!("{}: ", missing.display())),
        "{e}"
    );
}

#[test]
fn errors_name_the_line() {
    let cases: &[(&str, usize, &str)] = &[
        // TOML syntax.
        ("name = \"x\"\nbase = \"cia402\"\n[codes\n", 3, ""),
        // A required key missing: reported at the top of the document.
        ("base = \"cia402\"\n", 1, "name"),
        // An unknown key.
        ("name = \"x\"\n\nbsae = \"cia402\"\n", 3, "bsae"),
        // Wrong type.
        ("name = \"x\"\nzero_bytes = \"4-7\"\n", 2, ""),
        (
            "name = \"x\"\nbase = \"kollmorgne\"\n",
            2,
            "unknown base profile",
        ),
        ("name = \"x\"\ntables = \"cia401\"\n", 2, "unknown tables"),
        ("name = \"bad name\"\n", 1, "profile name"),
        (
            "name = \"x\"\n[codes]\n\"0x4310\" = { text = \"a\" }\n\"4311\" = { text = \"b\" }\n",
            4,
            "hexadecimal",
        ),
        (
            "name = \"x\"\n[codes]\n\"0x4310\" = { text = \"a\", category = 300 }\n",
            3,
            "category 300",
        ),
        (
            "name = \"x\"\n[codes]\n\"0x4310\" = { text = \"a\", colour = 1 }\n",
            3,
            "colour",
        ),
        (
            "name = \"x\"\n\n[[field]]\nname = \"a\"\nbyte = 8\n",
            5,
            "outside the manufacturer bytes",
        ),
        (
            "name = \"x\"\n[[field]]\nname = \"a\"\nbyte = 6\nsize = 4\n",
            5,
            "does not fit",
        ),
        (
            "name = \"x\"\n[[field]]\nname = \"Bad-Key\"\nbyte = 3\n",
            3,
            "JSON key",
        ),
        (
            "name = \"x\"\n[[field]]\nname = \"a\"\nbyte = 3\nrole = \"severity\"\n",
            5,
            "unknown role",
        ),
        (
            "name = \"x\"\n[[field]]\nname = \"a\"\nbyte = 3\n[field.values]\n\"1\" = \"one\"\n\"two\" = \"2\"\n",
            7,
            "not a number",
        ),
        (
            "name = \"x\"\n[[field]]\nname = \"a\"\nbyte = 3\n[field.values]\n\"0x100\" = \"big\"\n",
            6,
            "does not fit",
        ),
        (
            "name = \"x\"\n[[field]]\nname = \"a\"\nbyte = 3\n[field.values]\n\"0x30-0x3F\" = \"r\"\n\"0x35\" = \"in r\"\n",
            7,
            "overlap",
        ),
        // The second field collides with the inherited category byte.
        (
            "name = \"x\"\nbase = \"kollmorgen\"\n\n[[field]]\nname = \"axis\"\nbyte = 3\n",
            4,
            "share a byte",
        ),
        (
            "name = \"x\"\n[[field]]\nname = \"a\"\nbyte = 3\n[[field]]\nname = \"a_text\"\nbyte = 4\n",
            5,
            "same JSON key",
        ),
        (
            "name = \"x\"\nbase = \"stoeber\"\nzero_bytes = [5, 3]\n",
            3,
            "byte 3 is in zero_bytes but a field uses it",
        ),
        ("name = \"x\"\nzero_bytes = [2]\n", 2, "out of range"),
        (
            "name = \"x\"\nreserved_register_bits = [8]\n",
            2,
            "out of range",
        ),
        (
            "name = \"x\"\n[register_bits]\n\"9\" = \"nine\"\n",
            3,
            "bit number",
        ),
        (
            "name = \"x\"\nmanufacturer_low_bytes = [0x90, 0x80]\n",
            2,
            "first <= last",
        ),
    ];
    for (text, line, needle) in cases {
        let e = parse_err(text);
        assert_eq!(e.line(), Some(*line), "{text:?}: {e}");
        assert!(e.message().contains(needle), "{text:?}: {e}");
        assert!(
            e.to_string().starts_with(&format!("bad.toml:{line}: ")),
            "{e}"
        );
    }
}

#[test]
fn user_profiles_without_base_start_from_cia402() {
    let p = Profile::parse(
        "plain.toml",
        "name = \"plain\"\n[[field]]\nname = \"code\"\nbyte = 3\nsize = 2\n",
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p.base(), None);
    assert_eq!(p.tables(), Tables::Cia402);
    assert_eq!(p.summary(), "user profile");
    assert_eq!(
        p.decode_manufacturer(&frame(&[0x10, 0x43, 0x09, 0x34, 0x12]))
            .map(|d| d.fields),
        Some(vec![("code".to_owned(), int(0x1234))])
    );
    // Too short for the two-byte field: nothing decoded.
    assert_eq!(
        p.decode_manufacturer(&frame(&[0x10, 0x43, 0x09, 0x34])),
        None
    );
    // A category field without value names: any non-zero value counts.
    let p = Profile::parse(
            "cat.toml",
            "name = \"cat\"\nbase = \"cia301\"\n[[field]]\nname = \"severity\"\nbyte = 7\nrole = \"category\"\n",
        )
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p.summary(), "user profile based on cia301");
    assert_eq!(p.tables(), Tables::Cia301);
    assert_eq!(
        p.category(&frame(&[0x10, 0x43, 0x09, 0, 0, 0, 0, 3])),
        Some(3)
    );
    assert_eq!(p.category(&frame(&[0x10, 0x43, 0x09, 0, 0, 0, 0, 0])), None);
}

#[test]
fn arbitrary_frames_never_panic() {
    let user = Profile::parse("acme.toml", ACME).unwrap_or_else(|e| panic!("{e}"));
    let all: Vec<&Profile> = Profile::builtins().iter().chain([&user]).collect();
    for len in 3..=8usize {
        for fill in [0x00u8, 0x01, 0x7F, 0x80, 0xFF] {
            let data: Vec<u8> = (0..len).map(|i| fill.wrapping_add(i as u8)).collect();
            let e = frame(&data);
            for p in &all {
                let _ = p.decode_manufacturer(&e);
                let _ = p.category(&e);
                let _ = p.status_bit(&e);
                let _ = p.describe(e.code);
                let mut out = Vec::new();
                p.frame_warnings(&e, &mut out);
            }
        }
    }
    for bit in 0..=255u8 {
        for p in &all {
            let _ = p.register_bit_name(bit);
        }
    }
}
