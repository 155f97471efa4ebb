//! The committed fixtures are exactly what examples/make_fixtures.rs generates (the generator
//! is deterministic and nobody edited a fixture by hand).

use crate::common;

#[allow(dead_code)]
#[path = "../../examples/make_fixtures.rs"]
mod make_fixtures;

#[test]
fn committed_fixtures_match_the_generator() {
    let dir = tempfile::tempdir().unwrap();
    let src = common::fixtures().join("source/astronaut.png");
    make_fixtures::generate(dir.path(), &src).unwrap();
    let mut n = 0;
    for e in std::fs::read_dir(dir.path()).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_owned();
        let committed = common::fixtures().join(&name);
        let fresh = std::fs::read(&p).unwrap();
        let old = std::fs::read(&committed)
            .unwrap_or_else(|_| panic!("{} is generated but not committed", committed.display()));
        assert!(
            fresh == old,
            "{} differs from the generator's output: run \
             `cargo run --release --example make_fixtures -- fixtures/`",
            committed.display()
        );
        n += 1;
    }
    assert!(n >= 12, "only {n} fixtures generated");
}
