//! Writes the seeds of every fuzz target (`sinscal_lab::fuzz::seeds`) to `corpus/TARGET/seed`.
fn main() {
    for (target, _, seed) in sinscal_lab::fuzz::seeds() {
        let dir = std::path::Path::new("corpus").join(target);
        std::fs::create_dir_all(&dir).expect("the corpus folder can be made");
        std::fs::write(dir.join("seed"), seed).expect("the seed can be written");
    }
}
