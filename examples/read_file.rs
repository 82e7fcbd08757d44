//! Read a measurement file as `fit` does and print how many samples it holds and how long
//! the reading took (wall seconds, MB/s of the file's size): the reading alone, for timing
//! readers (benches/merl_read.sh, benches/csv_read.sh).
//! Usage: `read_file FILE [CHANNEL]`.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = std::path::PathBuf::from(args.next().ok_or("usage: read_file FILE [CHANNEL]")?);
    let opts = goniofit::ReadOptions {
        channel: args.next(),
        require_value: true,
        ..Default::default()
    };
    let t0 = std::time::Instant::now();
    let ds = goniofit::read(&path, &opts)?;
    let seconds = t0.elapsed().as_secs_f64();
    let mb = std::fs::metadata(&path)?.len() as f64 / 1e6;
    println!(
        "{} samples, read in {seconds:.4} s ({:.1} MB/s)",
        ds.len(),
        mb / seconds
    );
    Ok(())
}
