//! Mistakes in the declarations are compile errors that point at the field and say what is
//! wrong; each case in tests/ui/ pins one message (`TRYBUILD=overwrite` regenerates them).

#[test]
fn declaration_mistakes_are_compile_errors_at_the_field() {
    let t = trybuild::TestCases::new();
    t.compile_fail("tests/ui/*.rs");
}
