fn main() {
    let which = std::env::args().nth(1).unwrap();
    let n: usize = std::env::args().nth(2).unwrap().parse().unwrap();
    let lines = if which == "coast" {
        sweeptin::synth::coastline(n, 1)
    } else {
        sweeptin::synth::contours(n, 1)
    };
    for l in lines {
        for p in l {
            println!("{} {} {}", p[0], p[1], p[2]);
        }
        println!();
    }
}
