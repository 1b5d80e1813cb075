//! FIRES smart-pen firmware for the STM32F103VE board (hardware-docs/board.md).
//!
//! Thin glue: every decision is made by `fires-pen-core`; this file binds it to embassy-stm32 peripherals.
//!
//! | task            | owns                                   | does                                                    |
//! |-----------------|----------------------------------------|---------------------------------------------------------|
//! | `sampler_task`  | I2C1 (DMA) + the three sensor drivers  | 100 Hz ticks, frames packets into `FRAMES` when streaming |
//! | `radio_task`    | USART1 (DMA TX, DMA ring RX), WT12 RESET | provisions the WT12, then writes `FRAMES`, routes RX bytes |
//! | `control_task`  | status LED, IR LEDs, power latch       | mode controller, status packets, auto-off, LED patterns |
//! | `button_task`   | four EXTI inputs                       | debounce and long press                                 |
//! | `feedback_task` | TIM3 PWM (motor), TIM4 PWM (speaker)   | plays the feedback queue                                |
//! | `watchdog_task` | IWDG                                   | feeds it only while sampler, radio TX and command RX report alive |
//!
//! Frame ordering: sensor and status frames are built and queued inside one critical section (`SHARED`), so the
//! order in `FRAMES` is the order the counters were assigned, which the host's decoder relies on.
//!
//! Timestamps: embassy-time runs on the TIM2 hardware counter at 1 MHz (`time-driver-tim2`,
//! `tick-hz-1_000_000`); `Instant::now()` taken right after each tick wakes the sampler is that counter's value.
#![no_std]
#![no_main]

use core::cell::RefCell;
use core::sync::atomic::{AtomicBool, AtomicU8, Ordering};

use defmt::{info, warn};
use defmt_rtt as _;
use embassy_embedded_hal::shared_bus::asynch::i2c::I2cDevice;
use embassy_executor::Spawner;
use embassy_futures::join::join;
use embassy_futures::select::{select, select4, Either};
use embassy_stm32::adc::{self, Adc, SampleTime};
use embassy_stm32::exti::{self, ExtiInput};
use embassy_stm32::gpio::{Level, Output, OutputType, Pull, Speed};
use embassy_stm32::i2c::{self, I2c};
use embassy_stm32::mode::Async;
use embassy_stm32::time::{khz, Hertz};
use embassy_stm32::timer::simple_pwm::{PwmPin, SimplePwm};
use embassy_stm32::usart::{self, RingBufferedUartRx, Uart, UartTx};
use embassy_stm32::wdg::IndependentWatchdog;
use embassy_stm32::{bind_interrupts, dma, interrupt, peripherals, Config, Peri};
use embassy_sync::blocking_mutex::raw::{CriticalSectionRawMutex, NoopRawMutex};
use embassy_sync::blocking_mutex::Mutex as BlockingMutex;
use embassy_sync::channel::Channel;
use embassy_sync::mutex::Mutex;
use embassy_sync::signal::Signal;
use embassy_time::{Delay, Duration, Instant, Timer};
use fires_pen_core::buttons::{ButtonEvents, Debouncer, POLL_PERIOD};
use fires_pen_core::commands::{Controller, Effects};
use fires_pen_core::drivers::bus::I2cRegisters;
use fires_pen_core::drivers::{l3g4200d, lis3lv02dl, mag3110};
use fires_pen_core::drivers::{l3g4200d::L3g4200d, lis3lv02dl::Lis3lv02dl, mag3110::Mag3110};
use fires_pen_core::feedback::{self, FeedbackQueue};
use fires_pen_core::iwrap::{self, LinkChange, ModemPort, RxRouter};
use fires_pen_core::power::{battery_mv, BatteryMonitor};
use fires_pen_core::sampler::{sample_loop, FrameSink, Framer, PenImu, TICK};
use fires_pen_core::status::{StatusInputs, StatusReporter};
use fires_pen_core::status_led::{color_at, Color};
use fires_protocol::{Command, Health, StateFlags, StatusReason, FRAME_LEN};
use panic_probe as _;
use static_cell::StaticCell;

bind_interrupts!(struct Irqs {
    I2C1_EV => i2c::EventInterruptHandler<peripherals::I2C1>;
    I2C1_ER => i2c::ErrorInterruptHandler<peripherals::I2C1>;
    USART1 => usart::InterruptHandler<peripherals::USART1>;
    DMA1_CHANNEL4 => dma::InterruptHandler<peripherals::DMA1_CH4>;
    DMA1_CHANNEL5 => dma::InterruptHandler<peripherals::DMA1_CH5>;
    DMA1_CHANNEL6 => dma::InterruptHandler<peripherals::DMA1_CH6>;
    DMA1_CHANNEL7 => dma::InterruptHandler<peripherals::DMA1_CH7>;
    EXTI0 => exti::InterruptHandler<interrupt::typelevel::EXTI0>;
    EXTI2 => exti::InterruptHandler<interrupt::typelevel::EXTI2>;
    EXTI3 => exti::InterruptHandler<interrupt::typelevel::EXTI3>;
    EXTI4 => exti::InterruptHandler<interrupt::typelevel::EXTI4>;
    ADC1_2 => adc::InterruptHandler<peripherals::ADC1>;
});

type Cs = CriticalSectionRawMutex;
type SensorBus = I2cDevice<'static, NoopRawMutex, I2c<'static, Async, i2c::Master>>;
type Imu = PenImu<I2cRegisters<SensorBus>, I2cRegisters<SensorBus>, I2cRegisters<SensorBus>>;

/// Frames waiting for the UART: 16 frames = 160 ms of stream. Full means the radio is backed up.
static FRAMES: Channel<Cs, [u8; FRAME_LEN], 16> = Channel::new();
/// Inputs of the control task.
static EVENTS: Channel<Cs, Event, 16> = Channel::new();
/// Counter/status state shared by the sampler and the control task.
static SHARED: BlockingMutex<Cs, RefCell<Option<Shared>>> = BlockingMutex::new(RefCell::new(None));
/// Vibration and beep queue.
static FEEDBACK: BlockingMutex<Cs, RefCell<FeedbackQueue>> =
    BlockingMutex::new(RefCell::new(FeedbackQueue::new()));
/// Wakes the feedback task after a push.
static FEEDBACK_KICK: Signal<Cs, ()> = Signal::new();
/// Whether the SPP link is up (frames are only written then).
static CONNECTED: AtomicBool = AtomicBool::new(false);

/// Liveness bits for the watchdog.
const ALIVE_SAMPLER: u8 = 1 << 0;
const ALIVE_RADIO_TX: u8 = 1 << 1;
const ALIVE_COMMAND_RX: u8 = 1 << 2;
static ALIVE: AtomicU8 = AtomicU8::new(0);
/// Bits the watchdog waits for; the radio bits join once provisioning (up to ~12 s) has finished.
static REQUIRED: AtomicU8 = AtomicU8::new(ALIVE_SAMPLER);

enum Event {
    Command(Command),
    Link(LinkChange),
    Buttons(ButtonEvents),
    RadioReady(bool),
}

struct Shared {
    framer: Framer,
    status: StatusReporter,
    inputs: StatusInputs,
    streaming: bool,
    low_battery: bool,
}

/// The frame queue as the core's sink: a frame is queued whole or refused.
struct FrameTx;

impl FrameSink for FrameTx {
    fn try_send(&mut self, frame: &[u8; FRAME_LEN]) -> bool {
        FRAMES.try_send(*frame).is_ok()
    }
}

fn alive(bit: u8) {
    ALIVE.fetch_or(bit, Ordering::Relaxed);
}

#[embassy_executor::main]
async fn main(spawner: Spawner) {
    let mut config = Config::default();
    {
        use embassy_stm32::rcc::*;
        // 8 MHz crystal -> 72 MHz SYSCLK, APB1 36 MHz, APB2 72 MHz.
        config.rcc.hse = Some(Hse {
            freq: Hertz(8_000_000),
            mode: HseMode::Oscillator,
        });
        config.rcc.pll = Some(Pll {
            src: PllSource::HSE,
            prediv: PllPreDiv::DIV1,
            mul: PllMul::MUL9,
        });
        config.rcc.sys = Sysclk::PLL1_P;
        config.rcc.ahb_pre = AHBPrescaler::DIV1;
        config.rcc.apb1_pre = APBPrescaler::DIV2;
        config.rcc.apb2_pre = APBPrescaler::DIV1;
    }
    let p = embassy_stm32::init(config);
    // Hold the power latch first: the pen stays on after the power button is released.
    let power_hold = Output::new(p.PC2, Level::High, Speed::Low);
    info!(
        "FIRES pen firmware {}",
        fires_pen_core::board::FIRMWARE_VERSION
    );

    let boot = Instant::now();
    let led = [
        Output::new(p.PD12, Level::Low, Speed::Low), // red
        Output::new(p.PD13, Level::Low, Speed::Low), // green
        Output::new(p.PD14, Level::Low, Speed::Low), // yellow
    ];
    let ir_leds = Output::new(p.PD8, Level::Low, Speed::Low);

    // Sensors on I2C1 (PB6 SCL, PB7 SDA), 400 kHz, DMA1 channels 6/7.
    let mut i2c_cfg = i2c::Config::default();
    i2c_cfg.frequency = khz(400);
    let i2c = I2c::new(p.I2C1, p.PB6, p.PB7, p.DMA1_CH6, p.DMA1_CH7, Irqs, i2c_cfg);
    static I2C_BUS: StaticCell<Mutex<NoopRawMutex, I2c<'static, Async, i2c::Master>>> =
        StaticCell::new();
    let bus = I2C_BUS.init(Mutex::new(i2c));
    let mut imu: Imu = PenImu {
        accel: Lis3lv02dl::new(I2cRegisters::st(
            I2cDevice::new(bus),
            lis3lv02dl::I2C_ADDRESS,
        )),
        gyro: L3g4200d::new(I2cRegisters::st(I2cDevice::new(bus), l3g4200d::I2C_ADDRESS)),
        mag: Mag3110::new(I2cRegisters::plain(
            I2cDevice::new(bus),
            mag3110::I2C_ADDRESS,
        )),
    };
    let health = init_sensors(&mut imu).await;
    info!("sensor health {:#08b}", health.0);

    SHARED.lock(|s| {
        s.replace(Some(Shared {
            framer: Framer::new(),
            status: StatusReporter::new(boot),
            inputs: StatusInputs {
                health,
                ..Default::default()
            },
            streaming: false,
            low_battery: false,
        }))
    });

    // WT12 on USART1 (PA9 TX, PA10 RX), DMA1 channels 4 (TX) / 5 (RX ring). RESET on PC0 (active high).
    let mut uart_cfg = usart::Config::default();
    uart_cfg.baudrate = fires_protocol::LINK_BAUD;
    let uart = unwrap_or_halt(Uart::new(
        p.USART1, p.PA10, p.PA9, p.DMA1_CH4, p.DMA1_CH5, Irqs, uart_cfg,
    ));
    let (tx, rx) = uart.split();
    static RX_RING: StaticCell<[u8; 256]> = StaticCell::new();
    let rx = rx.into_ring_buffered(RX_RING.init([0; 256]));
    let wt12_reset = Output::new(p.PC0, Level::Low, Speed::Low);
    // PIO6 of the WT12 is its DTR input (SET CONTROL ESCAPE - 40 1); held low = stay in data mode.
    let wt12_dtr = Output::new(p.PC1, Level::Low, Speed::Low);

    let buttons = [
        ExtiInput::new(p.PA0, p.EXTI0, Pull::Down, Irqs), // button 1 = power
        ExtiInput::new(p.PE2, p.EXTI2, Pull::Down, Irqs),
        ExtiInput::new(p.PE3, p.EXTI3, Pull::Down, Irqs),
        ExtiInput::new(p.PE4, p.EXTI4, Pull::Down, Irqs),
    ];

    // Motor: TIM3 CH1 on PA6 at 20 kHz (inaudible). Speaker: TIM4 CH3 on PB8, frequency per tone.
    let motor = SimplePwm::new(
        p.TIM3,
        Some(PwmPin::new(p.PA6, OutputType::PushPull)),
        None,
        None,
        None,
        khz(20),
        Default::default(),
    );
    let speaker = SimplePwm::new(
        p.TIM4,
        None,
        None,
        Some(PwmPin::new(p.PB8, OutputType::PushPull)),
        None,
        khz(2),
        Default::default(),
    );

    let wdg = IndependentWatchdog::new(p.IWDG, 1_000_000);
    // Battery: VBAT / 2 on PB0 (ADC12_IN8), ratioed against VREFINT.
    let battery = BatteryAdc {
        adc: Adc::new(p.ADC1),
        pin: p.PB0,
    };

    FEEDBACK.lock(|q| q.borrow_mut().push_pattern(feedback::BOOT));
    spawner.spawn(unwrap_or_halt(watchdog_task(wdg)));
    spawner.spawn(unwrap_or_halt(feedback_task(motor, speaker)));
    spawner.spawn(unwrap_or_halt(sampler_task(imu)));
    spawner.spawn(unwrap_or_halt(button_task(buttons)));
    spawner.spawn(unwrap_or_halt(radio_task(Radio {
        tx,
        rx,
        reset: wt12_reset,
        _dtr: wt12_dtr,
    })));
    spawner.spawn(unwrap_or_halt(control_task(
        boot, health, led, ir_leds, power_hold, battery,
    )));
}

fn unwrap_or_halt<T, E: core::fmt::Debug>(r: Result<T, E>) -> T {
    match r {
        Ok(v) => v,
        Err(e) => defmt::panic!("init failed: {}", defmt::Debug2Format(&e)),
    }
}

/// Identity checks and self-tests (the pen must lie still for the ~0.5 s this takes).
async fn init_sensors(imu: &mut Imu) -> Health {
    let mut h = 0u8;
    let mut delay = Delay;
    if imu.accel.identify().await.is_ok() {
        h |= Health::ACCEL_OK;
        match imu.accel.self_test(&mut delay).await {
            Ok(_) => h |= Health::ACCEL_SELF_TEST,
            Err(e) => warn!("accelerometer self-test: {}", defmt::Debug2Format(&e)),
        }
    }
    if imu.gyro.identify().await.is_ok() {
        h |= Health::GYRO_OK;
        match imu.gyro.self_test(&mut delay).await {
            Ok(_) => h |= Health::GYRO_SELF_TEST,
            Err(e) => warn!("gyroscope self-test: {}", defmt::Debug2Format(&e)),
        }
    }
    if imu.mag.identify().await.is_ok() && imu.mag.configure().await.is_ok() {
        h |= Health::MAG_OK;
        Timer::after_millis(30).await;
        if imu.mag.plausibility_check(&mut delay).await.is_ok() {
            h |= Health::MAG_SELF_TEST;
        }
    }
    Health(h)
}

#[embassy_executor::task]
async fn watchdog_task(mut wdg: IndependentWatchdog<'static, peripherals::IWDG>) {
    wdg.unleash();
    loop {
        Timer::after_millis(250).await;
        let required = REQUIRED.load(Ordering::Relaxed);
        if ALIVE.swap(0, Ordering::Relaxed) & required == required {
            wdg.pet();
        }
    }
}

#[embassy_executor::task]
async fn sampler_task(mut imu: Imu) {
    sample_loop(&mut imu, TICK, |reading, at| {
        alive(ALIVE_SAMPLER);
        SHARED.lock(|s| {
            let mut s = s.borrow_mut();
            let Some(s) = s.as_mut() else { return };
            if !s.streaming {
                return;
            }
            match reading {
                Ok(sample) => {
                    s.framer
                        .sensor(&sample, at.as_micros() as u32, &mut FrameTx);
                }
                Err(_) => {
                    s.framer.read_failed();
                    s.inputs.health.0 |= Health::READ_ERROR;
                }
            }
        });
        true
    })
    .await;
}

#[embassy_executor::task]
async fn button_task(mut buttons: [ExtiInput<'static, Async>; 4]) {
    let read = |b: &[ExtiInput<'static, Async>; 4]| b.each_ref().map(|p| p.is_high());
    let mut deb = Debouncer::new(read(&buttons), Instant::now());
    loop {
        if deb.busy() {
            Timer::after(POLL_PERIOD).await;
        } else {
            let [a, b, c, d] = &mut buttons;
            select4(
                a.wait_for_any_edge(),
                b.wait_for_any_edge(),
                c.wait_for_any_edge(),
                d.wait_for_any_edge(),
            )
            .await;
        }
        let ev = deb.update(read(&buttons), Instant::now());
        if ev != ButtonEvents::default() {
            EVENTS.send(Event::Buttons(ev)).await;
        }
    }
}

#[embassy_executor::task]
async fn feedback_task(
    mut motor: SimplePwm<'static, peripherals::TIM3>,
    mut speaker: SimplePwm<'static, peripherals::TIM4>,
) {
    let mut tone = None;
    loop {
        let (out, next) = FEEDBACK.lock(|q| {
            let mut q = q.borrow_mut();
            (q.poll(Instant::now()), q.next_change())
        });
        if out.motor {
            motor.ch1().set_duty_cycle_percent(80);
            motor.ch1().enable();
        } else {
            motor.ch1().disable();
        }
        if out.tone_hz != tone {
            tone = out.tone_hz;
            match tone {
                Some(hz) => {
                    speaker.set_frequency(Hertz(u32::from(hz.clamp(100, 10_000))));
                    speaker.ch3().set_duty_cycle_percent(50);
                    speaker.ch3().enable();
                }
                None => speaker.ch3().disable(),
            }
        }
        match next {
            Some(t) => {
                select(Timer::at(t), FEEDBACK_KICK.wait()).await;
            }
            None => FEEDBACK_KICK.wait().await,
        }
    }
}

/// The WT12's UART and control lines, as the core's [`ModemPort`].
struct Radio {
    tx: UartTx<'static, Async>,
    rx: RingBufferedUartRx<'static>,
    reset: Output<'static>,
    _dtr: Output<'static>,
}

impl ModemPort for Radio {
    type Error = usart::Error;
    async fn write_all(&mut self, bytes: &[u8]) -> Result<(), usart::Error> {
        self.tx.write(bytes).await
    }
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, usart::Error> {
        self.rx.read(buf).await
    }
    fn set_baud(&mut self, baud: u32) {
        // TX and RX share USART1: one BRR.
        if self.tx.set_baudrate(baud).is_err() {
            warn!("baud {} not reachable", baud);
        }
    }
    async fn reset_module(&mut self) {
        // WT12 RESET is active high and must be held > 5 ms.
        self.reset.set_high();
        Timer::after_millis(10).await;
        self.reset.set_low();
    }
}

#[embassy_executor::task]
async fn radio_task(mut radio: Radio) {
    let result = iwrap::provision_module(&mut radio, iwrap::Config::FIRES).await;
    match result {
        Ok(baud) => info!("WT12 provisioned at {} baud", baud),
        Err(e) => warn!("WT12 provisioning failed: {}", e),
    }
    EVENTS.send(Event::RadioReady(result.is_ok())).await;
    REQUIRED.fetch_or(ALIVE_RADIO_TX | ALIVE_COMMAND_RX, Ordering::Relaxed);
    let Radio { mut tx, mut rx, .. } = radio;
    let tx_loop = async {
        loop {
            alive(ALIVE_RADIO_TX);
            match select(FRAMES.receive(), Timer::after_millis(100)).await {
                Either::First(frame) => {
                    // Frames queued just before a disconnect are discarded, never written to command mode.
                    if CONNECTED.load(Ordering::Relaxed) && tx.write(&frame).await.is_err() {
                        warn!("uart tx error");
                    }
                }
                Either::Second(()) => {}
            }
        }
    };
    let rx_loop = async {
        let mut router = RxRouter::new();
        let mut buf = [0u8; 32];
        loop {
            alive(ALIVE_COMMAND_RX);
            match select(rx.read(&mut buf), Timer::after_millis(100)).await {
                Either::First(Ok(n)) => {
                    for &b in &buf[..n] {
                        let (change, cmd) = router.push(b);
                        if let Some(c) = change {
                            CONNECTED.store(c == LinkChange::Connected, Ordering::Relaxed);
                            EVENTS.send(Event::Link(c)).await;
                        }
                        if let Some(c) = cmd {
                            EVENTS.send(Event::Command(c)).await;
                        }
                    }
                }
                Either::First(Err(_)) => warn!("uart rx error (overrun or noise)"),
                Either::Second(()) => {}
            }
        }
    };
    join(tx_loop, rx_loop).await;
}

/// The battery divider's ADC input.
struct BatteryAdc {
    adc: Adc<'static, peripherals::ADC1>,
    pin: Peri<'static, peripherals::PB0>,
}

impl BatteryAdc {
    async fn read_mv(&mut self) -> u16 {
        let mut vref = self.adc.enable_vref();
        let raw_ref = self.adc.read(&mut vref, SampleTime::CYCLES239_5).await;
        let raw_bat = self.adc.read(&mut self.pin, SampleTime::CYCLES239_5).await;
        battery_mv(raw_bat, raw_ref)
    }
}

#[embassy_executor::task]
async fn control_task(
    boot: Instant,
    health: Health,
    mut led: [Output<'static>; 3],
    mut ir_leds: Output<'static>,
    mut power_hold: Output<'static>,
    mut battery_adc: BatteryAdc,
) {
    let mut ctl = Controller::new(boot);
    let mut battery = BatteryMonitor::new();
    let sensors_ok = health.has(Health::ACCEL_OK | Health::GYRO_OK | Health::MAG_OK);
    let mut boot_status_sent = false;
    loop {
        let now = Instant::now();
        // LED
        let (state, since) = ctl.led();
        let (color, led_next) = color_at(state, since, now);
        for (i, pin) in led.iter_mut().enumerate() {
            let on = matches!(
                (i, color),
                (0, Color::Red) | (1, Color::Green) | (2, Color::Yellow)
            );
            pin.set_level(if on { Level::High } else { Level::Low });
        }
        ir_leds.set_level(if ctl.ir_leds() {
            Level::High
        } else {
            Level::Low
        });
        // Status packets (only while a host listens: in command mode the module would parse them).
        let connected = ctl.connected();
        let periodic = SHARED.lock(|s| {
            s.borrow()
                .as_ref()
                .is_some_and(|s| s.status.periodic_due(now))
        });
        if periodic {
            battery.update(battery_adc.read_mv().await);
            SHARED.lock(|s| {
                if let Some(s) = s.borrow_mut().as_mut() {
                    s.inputs.battery_mv = battery.mv();
                    s.low_battery = battery.low();
                }
            });
            send_status(StatusReason::Periodic, &ctl, connected);
            if battery.critical() {
                let fx = ctl.on_battery_critical(Instant::now());
                handle_effects(fx, &mut power_hold).await;
            }
        }
        // Repeats of the latest button change (hardware-docs/protocol.md §1.2).
        if connected {
            SHARED.lock(|s| {
                if let Some(s) = s.borrow_mut().as_mut() {
                    let inputs = s.inputs;
                    let Shared { framer, status, .. } = s;
                    status.send_repeat(&inputs, framer, now, &mut FrameTx);
                }
            });
        }
        // Auto-off
        let fx = ctl.poll(now);
        handle_effects(fx, &mut power_hold).await;

        let status_next = SHARED.lock(|s| {
            s.borrow()
                .as_ref()
                .map_or(now + Duration::from_secs(1), |s| {
                    let p = s.status.next_periodic();
                    s.status.next_repeat().map_or(p, |r| r.min(p))
                })
        });
        let mut wake = status_next.min(ctl.next_deadline());
        if let Some(t) = led_next {
            wake = wake.min(t);
        }
        let ev = match select(EVENTS.receive(), Timer::at(wake)).await {
            Either::First(ev) => ev,
            Either::Second(()) => continue,
        };
        let now = Instant::now();
        let fx = match ev {
            Event::RadioReady(ok) => {
                ctl.startup_done(sensors_ok, ok, now);
                Effects::default()
            }
            Event::Link(change) => {
                FEEDBACK.lock(|q| ctl.on_link(change, &mut q.borrow_mut(), now));
                FEEDBACK_KICK.signal(());
                if change == LinkChange::Connected && !boot_status_sent {
                    boot_status_sent = true;
                    Effects {
                        status: Some(StatusReason::Boot),
                        power_off: None,
                    }
                } else {
                    Effects::default()
                }
            }
            Event::Command(cmd) => {
                let fx = FEEDBACK.lock(|q| ctl.on_command(cmd, &mut q.borrow_mut(), now));
                FEEDBACK_KICK.signal(());
                fx
            }
            Event::Buttons(b) => {
                if let Some(state) = b.changed {
                    SHARED.lock(|s| {
                        if let Some(s) = s.borrow_mut().as_mut() {
                            s.inputs.buttons = state;
                        }
                    });
                }
                ctl.on_buttons(b, now)
            }
        };
        SHARED.lock(|s| {
            if let Some(s) = s.borrow_mut().as_mut() {
                s.streaming = ctl.streaming();
                s.inputs.flags = ctl.flags();
            }
        });
        if let Some(reason) = fx.status {
            send_status(reason, &ctl, ctl.connected());
        }
        handle_effects(fx, &mut power_hold).await;
    }
}

fn send_status(reason: StatusReason, ctl: &Controller, connected: bool) {
    SHARED.lock(|s| {
        let mut s = s.borrow_mut();
        let Some(s) = s.as_mut() else { return };
        s.inputs.flags = ctl.flags();
        if s.low_battery {
            s.inputs.flags.0 |= StateFlags::LOW_BATTERY;
        }
        if connected {
            let inputs = s.inputs;
            let Shared { framer, status, .. } = s;
            status.send(reason, &inputs, framer, Instant::now(), &mut FrameTx);
            s.inputs.health.0 &= !Health::READ_ERROR;
        } else if reason == StatusReason::Periodic {
            // keep the schedule without queueing bytes nobody receives
            s.status.skip_periodic(Instant::now());
        }
    });
}

async fn handle_effects(fx: Effects, power_hold: &mut Output<'static>) {
    if let Some(reason) = fx.power_off {
        info!("power off: {}", reason);
        FEEDBACK.lock(|q| q.borrow_mut().push_pattern(feedback::POWER_OFF));
        FEEDBACK_KICK.signal(());
        Timer::after_millis(800).await;
        power_hold.set_low();
    }
}
