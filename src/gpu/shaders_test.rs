//! Every WGSL file parses, validates with naga and emits SPIR-V.

#[test]
fn every_wgsl_file_validates_and_emits_spirv() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("wgsl");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_none_or(|x| x != "wgsl") {
            continue;
        }
        let src = std::fs::read_to_string(&p).unwrap();
        let module = naga::front::wgsl::parse_str(&src)
            .unwrap_or_else(|e| panic!("{}: {}", p.display(), e.emit_to_string(&src)));
        let info = naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::empty(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("{}: {e:?}", p.display()));
        // Override constants (workgroup sizes) at their defaults, as a pipeline without values.
        let (module, info) = naga::back::pipeline_constants::process_overrides(
            &module,
            &info,
            None,
            &Default::default(),
        )
        .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        let spv = naga::back::spv::write_vec(&module, &info, &Default::default(), None)
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        assert_eq!(spv[0], 0x0723_0203, "{}: SPIR-V magic", p.display());
        n += 1;
    }
    assert!(n >= 4, "expected the kernel files in {}", dir.display());
}
