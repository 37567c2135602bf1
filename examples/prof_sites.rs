use qcs::sites::Quasicrystal;
fn main() {
    let q = Quasicrystal::new(1024, 1024).unwrap();
    for _ in 0..5 {
        let s = q.first(1_000_000);
        std::hint::black_box(s);
    }
}
