//! The `sixaxis` command.
fn main() {
    println!("sixaxis: under construction");
}
